"""The golden unit: a putter with known calibration that checks the station each shift.

A station's configuration may name one golden unit (``[golden]``): its serial number,
its reference offsets and sensitivities (counts, counts/g) and gyro biases (deg/s), the
tolerance each may differ by, and how often it is due. The station calibrates it like
any unit; :func:`disagreements` compares the run with the reference. A station whose
golden unit disagrees measures every unit wrongly by as much, so it locks until a
supervisor unlocks it with a reason (:mod:`station.loop.golden_lock`).

The golden unit is due (:func:`due`) when it has never agreed at this station, when its
last agreement is ``period_h`` hours old, or when a shift started since (``shift_starts``,
local times of day): the first unit of a shift is the golden unit.
"""

from datetime import datetime, time, timedelta

from pydantic import BaseModel, ConfigDict, Field

from station.domain.quality.days import wall_clock
from station.domain.record.records import SERIAL_PATTERN, RunRecord
from station.domain.sensors.sensor import AXES

Triple = tuple[float, float, float]


class GoldenUnit(BaseModel):
    """The golden unit of a station: reference values, tolerances, schedule."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    serial: str = Field(pattern=SERIAL_PATTERN)
    offset_counts: Triple
    sensitivity_counts_per_g: Triple
    gyro_bias_dps: Triple | None = None
    offset_tolerance_counts: float = Field(5.0, gt=0)
    sensitivity_tolerance_counts_per_g: float = Field(2.0, gt=0)
    gyro_bias_tolerance_dps: float = Field(0.2, gt=0)
    period_h: float = Field(8.0, gt=0, le=24 * 31, description="hours between checks")
    shift_starts: tuple[time, ...] = Field(
        (), description="local times of day a shift starts: its first unit is the golden one"
    )


def _fmt(value: float) -> str:
    return f"{value:.1f}" if abs(value) >= 1 else f"{value:.3g}"


def disagreements(unit: GoldenUnit, record: RunRecord) -> list[str]:
    """What in ``record`` disagrees with the golden unit's reference, in words.

    Each item names the quantity, the axis, the value and the reference with its
    tolerance ("offset x 2061.3 vs reference 2048.0 ± 5"); a run without coefficients
    (it failed before the solve, or was aborted) disagrees by its failures.
    """
    found: list[str] = []
    if record.coefficients is None:
        codes = ", ".join(f.code for f in record.failures) or "no coefficients"
        return [f"failed ({codes})"]
    pairs: list[tuple[str, tuple[float, ...], Triple | None, float]] = [
        (
            "offset",
            record.coefficients.offset.as_tuple(),
            unit.offset_counts,
            unit.offset_tolerance_counts,
        ),
        (
            "sensitivity",
            record.coefficients.sensitivity.as_tuple(),
            unit.sensitivity_counts_per_g,
            unit.sensitivity_tolerance_counts_per_g,
        ),
    ]
    if record.gyro is not None:
        bias = record.gyro.bias.as_tuple()
        pairs.append(("gyro bias", bias, unit.gyro_bias_dps, unit.gyro_bias_tolerance_dps))
    for name, measured, reference, tolerance in pairs:
        if reference is None:
            continue
        for axis, value, ref in zip(AXES, measured, reference, strict=True):
            if abs(value - ref) > tolerance:
                found.append(
                    f"{name} {axis} {_fmt(value)} vs reference {_fmt(ref)} ± {tolerance:g}"
                )
    return found


def due(unit: GoldenUnit, last_ok: datetime | None, now: datetime) -> bool:
    """Whether the golden unit must be checked before the next production unit.

    ``last_ok`` and ``now`` are aware datetimes; shift starts are in ``now``'s time zone
    (a ``last_ok`` that zone cannot show, of a clock set to the year 1 or 9999, in UTC).
    """
    if last_ok is None or now - last_ok >= timedelta(hours=unit.period_h):
        return True
    local = now.astimezone()
    since = wall_clock(last_ok, local.tzinfo)
    for offset in range((local.date() - since.date()).days + 1):
        day = since.date() + timedelta(days=offset)
        for start in unit.shift_starts:
            moment = datetime.combine(day, start, tzinfo=local.tzinfo)
            if since < moment <= local:
                return True
    return False
