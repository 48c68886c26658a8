"""How numbers read in the text and HTML renderings (the same in both)."""

from datetime import UTC, datetime
from typing import Protocol

from station.domain.quality.days import plant_time


def percent(value: float | None) -> str:
    """A fraction as a percentage with one decimal: ``0.875`` → ``87.5 %``."""
    return "–" if value is None else f"{100 * value:.1f} %"


def number(value: float | int | None, digits: int = 4) -> str:
    """``digits`` significant digits (integers in full); ``–`` for no value; zero is
    ``0``, never ``-0`` (a deviation rounded to nothing)."""
    if value is None:
        return "–"
    if isinstance(value, int):
        return str(value)
    return f"{value:.{digits}g}" if value else "0"


def seconds(value: float | None) -> str:
    """A duration in seconds with one decimal."""
    return "–" if value is None else f"{value:.1f} s"


def moment(value: datetime | None, zone: str = "UTC") -> str:
    """A moment to the second, in the plant's time ``zone`` (an IANA name; in UTC, and
    saying so, where that zone's wall clock would leave the years 1…9999)."""
    if value is None:
        return "–"
    local = plant_time(value, zone)  # the year as ISO, 0001: strftime's %Y may drop zeros
    return f"{local.date().isoformat()} {local:%H:%M:%S %Z}"


def clock(value: datetime, zone: str = "UTC") -> str:
    """A chart's time label in the plant's ``zone`` (as :func:`moment`): ``11-02 14:05``."""
    return plant_time(value, zone).strftime("%m-%d %H:%M")


def field(value: datetime | None, zone: str = "UTC") -> str:
    """A moment as the report's form shows it, in the plant's ``zone``, exactly: a date
    at midnight, else the date and time to the minute, second or microsecond
    (``2026-11-02``, ``2026-11-02T14:30``); with ``Z`` where it stays in UTC (beyond the
    zone's years 1…9999, :func:`station.domain.quality.days.plant_time`)."""
    if value is None:
        return ""
    local = plant_time(value, zone)
    suffix = "Z" if local.tzinfo is UTC else ""
    if (local.hour, local.minute, local.second, local.microsecond) == (0, 0, 0, 0) and not suffix:
        return local.date().isoformat()
    timespec = "auto" if local.second or local.microsecond else "minutes"
    return local.replace(tzinfo=None).isoformat(timespec=timespec) + suffix


class Reason(Protocol):
    """A failure reason as a run stores it
    (:class:`station.domain.record.records.FailureReason`)."""

    @property
    def code(self) -> str: ...
    @property
    def message(self) -> str: ...
    @property
    def measured(self) -> float | None: ...
    @property
    def lower(self) -> float | None: ...
    @property
    def upper(self) -> float | None: ...


def limits(lower: float | None, upper: float | None, digits: int = 6) -> str:
    """A check's limits as they read: ``1848 … 2248``, ``≤ 8``, ``≥ 5``; empty for none."""
    if lower is not None and upper is not None:
        return f"{number(lower, digits)} … {number(upper, digits)}"
    if upper is not None:
        return f"≤ {number(upper, digits)}"
    if lower is not None:
        return f"≥ {number(lower, digits)}"
    return ""


def reason(failure: Reason) -> str:
    """A failure reason as every page shows it: the station's own words (they name the
    axis, pose and value), then the value measured and the limits, when there are any:
    ``pose noise x (pose 3) 8.59057 counts (measured 8.59057, limit ≤ 8)``."""
    bounds = limits(failure.lower, failure.upper)
    facts = [] if failure.measured is None else [f"measured {number(failure.measured, 6)}"]
    if bounds:
        facts.append(f"limit {bounds}" if "…" not in bounds else f"limits {bounds}")
    text = failure.message or failure.code
    return f"{text} ({', '.join(facts)})" if facts else text
