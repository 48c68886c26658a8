"""Reading the report's time bounds: ISO dates or moments, in the plant's time zone
unless they name one (stored times stay UTC).

One place for the CLI (``--from``/``--to``) and the API (``from``/``to``): a bound must
read as a date or time and stay a valid moment once shifted to UTC (any moment of the
years 1…9999 in UTC, :data:`~station.domain.quality.days.FIRST` …
:data:`~station.domain.quality.days.LAST`: the report's days and shifts are clamped at
those ends); ``from`` must come before ``to``.
"""

import re
from datetime import UTC, date, datetime
from zoneinfo import ZoneInfo, ZoneInfoNotFoundError

from station.domain.errors import InputError
from station.domain.quality.days import FIRST, LAST, midnight

#: The most units a report lists (``--units``, ``units=``): years of a line's output.
MAX_LISTED_UNITS = 1_000_000


def plant_zone(name: str) -> str:
    """``name`` if it is an IANA time zone (``Europe/Berlin``, ``UTC``), else
    :class:`InputError`."""
    try:
        ZoneInfo(name)
    except (ZoneInfoNotFoundError, ValueError):
        raise InputError(
            f"time zone {name!r} is unknown: give an IANA name such as Europe/Berlin or UTC"
        ) from None
    return name


def parse_moment(text: str, *, name: str, zone: str = "UTC") -> datetime:
    """``2026-11-02`` (the plant's midnight, :func:`~station.domain.quality.days.midnight`:
    the first date's is :data:`~station.domain.quality.days.FIRST`), ``2026-11-02T14:00``
    (the plant's time) or with a zone, in UTC; ``zone`` is the plant's time zone (IANA name).

    Raises :class:`InputError` naming the option ``name`` for anything else, or for a
    moment outside :data:`~station.domain.quality.days.FIRST` …
    :data:`~station.domain.quality.days.LAST` (UTC).
    """
    try:
        return midnight(date.fromisoformat(text), zone)
    except ValueError:
        pass
    try:
        moment = datetime.fromisoformat(text)
    except ValueError:
        raise InputError(
            f"{name} {text!r} is not an ISO date or time (e.g. 2026-11-02 or "
            f"2026-11-02T14:00Z){_written_as_iso(text)}"
        ) from None
    try:
        local = moment.replace(tzinfo=ZoneInfo(zone)) if moment.tzinfo is None else moment
        return local.astimezone(UTC)
    except OverflowError:  # the zone shifts it past year 1 or 9999
        raise InputError(
            f"{name} {text!r} is out of range: give a moment from "
            f"{FIRST.isoformat()} to {LAST.isoformat()}"
        ) from None


def _written_as_iso(text: str) -> str:
    """For a day written the European way (``14.11.2026``), the same day as ISO."""
    found = re.fullmatch(r"\s*(\d{1,2})\.(\d{1,2})\.(\d{4})\s*", text)
    if found is None:
        return ""
    day, month, year = (int(part) for part in found.groups())
    try:
        return f": write {date(year, month, day).isoformat()}"
    except ValueError:
        return ""


def check_order(
    start: datetime | None, end: datetime | None, *, names: tuple[str, str] = ("--from", "--to")
) -> None:
    """:class:`InputError` unless ``start < end`` (either may be absent)."""
    if start is not None and end is not None and not start < end:
        first, last = (moment.isoformat(" ", "minutes") for moment in (start, end))
        raise InputError(
            f"{names[0]} {first} is not before {names[1]} {last}: the period holds nothing"
        )


def parse_period(
    since: str | None,
    until: str | None,
    *,
    names: tuple[str, str] = ("--from", "--to"),
    zone: str = "UTC",
) -> tuple[datetime | None, datetime | None]:
    """Both bounds (either may be absent; without a zone in the plant's ``zone``);
    :class:`InputError` unless ``since < until``."""
    start = parse_moment(since, name=names[0], zone=zone) if since else None
    end = parse_moment(until, name=names[1], zone=zone) if until else None
    check_order(start, end, names=names)
    return start, end
