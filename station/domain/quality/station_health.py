"""A station's health: its golden-unit checks over time against their reference, drift
warnings, its cycle times and the software and limits versions it runs.

The results server does not hold a station's golden-unit configuration (its reference
values live in the station's ``[golden]`` table, :mod:`station.domain.quality.golden`);
each check's verdict is the station's own judgement against that reference. On the page,
the reference each check is drawn against is the golden unit's **baseline**: the mean of
its first :data:`BASELINE_CHECKS` checks with coefficients at the station in the window.
A drift warning names an axis whose latest check is further from that baseline than the
golden unit's default tolerance (:class:`GoldenUnit`: 5 counts offset, 2 counts/g
sensitivity), or a latest check the station failed.
"""

from collections.abc import Sequence
from datetime import datetime
from functools import partial
from typing import Literal

from pydantic import Field

from station.domain.quality.figures import FigurePart
from station.domain.quality.golden import GoldenUnit
from station.domain.quality.split import GroupStats
from station.domain.sensors.sensor import AXES

#: The golden unit's first checks that make its baseline.
BASELINE_CHECKS = 3
OFFSET_TOLERANCE: float = GoldenUnit.model_fields["offset_tolerance_counts"].default
SENSITIVITY_TOLERANCE: float = GoldenUnit.model_fields["sensitivity_tolerance_counts_per_g"].default

Triple = tuple[float, float, float]


class GoldenCheck(FigurePart):
    """One golden-unit check: its coefficients' distance from the baseline."""

    run_id: str
    started_at: datetime
    serial: str
    verdict: str
    offset_deviation: Triple | None = Field(description="counts from the baseline, x y z")
    sensitivity_deviation: Triple | None = Field(description="counts/g from the baseline")


class VersionUse(FigurePart):
    """Runs of one software version and limits profile, first and last seen."""

    software_version: str
    limits: str
    runs: int
    first: datetime
    last: datetime


class DriftWarning(FigurePart):
    """A golden unit's latest check that failed, or an axis of it beyond tolerance of its
    baseline. ``checked_at`` is a moment (UTC): a page shows it in the plant's zone."""

    serial: str = Field(description="the golden unit")
    checked_at: datetime = Field(description="its latest check's start")
    problem: str = Field(description="what is wrong, in words (no time)")
    quantity: Literal["offset", "sensitivity"] | None = Field(
        default=None, description="the coefficient beyond tolerance (none: the check failed)"
    )
    axis: str | None = Field(default=None, description="its axis")
    deviation: float | None = Field(default=None, description="its deviation from the baseline")
    tolerance: float | None = Field(default=None, description="the tolerance it is beyond")


class StationHealth(FigurePart):
    """A station's health over its latest runs (:mod:`db.report.station_health`)."""

    station_id: str
    golden: list[GoldenCheck] = Field(description="the latest golden checks, oldest first")
    golden_limit: int
    drift: list[DriftWarning] = Field(description="drift warnings")
    cycle_seconds: GroupStats | None = Field(description="cycle time of production runs")
    cycle_runs: int = Field(description="production runs the cycle times come from (the latest)")
    versions: list[VersionUse]


def golden_checks(
    rows: Sequence[tuple[str, datetime, str, str, Triple | None, Triple | None]],
) -> tuple[list[GoldenCheck], list[DriftWarning]]:
    """The checks of ``rows`` (run id, start, serial, verdict, offset, sensitivity; oldest
    first) against each golden unit's baseline, and the drift warnings of its latest one."""
    by_serial: dict[str, list[tuple[Triple, Triple]]] = {}
    for *_, serial, _verdict, offset, sensitivity in rows:
        if offset is not None and sensitivity is not None:
            by_serial.setdefault(serial, []).append((offset, sensitivity))
    baselines = {
        serial: (
            _mean([o for o, _ in found[:BASELINE_CHECKS]]),
            _mean([s for _, s in found[:BASELINE_CHECKS]]),
        )
        for serial, found in by_serial.items()
    }
    checks = []
    for run_id, started_at, serial, verdict, offset, sensitivity in rows:
        base = baselines.get(serial)
        checks.append(
            GoldenCheck(
                run_id=run_id,
                started_at=started_at,
                serial=serial,
                verdict=verdict,
                offset_deviation=_less(offset, base[0]) if base and offset else None,
                sensitivity_deviation=_less(sensitivity, base[1]) if base and sensitivity else None,
            )
        )
    latest: dict[str, GoldenCheck] = {check.serial: check for check in checks}
    drift = []
    for serial, check in sorted(latest.items()):
        warning = partial(DriftWarning, serial=serial, checked_at=check.started_at)
        if check.verdict != "pass":
            drift.append(warning(problem="its latest check failed at the station"))
        coefficients: list[tuple[Literal["offset", "sensitivity"], Triple | None, float, str]] = [
            ("offset", check.offset_deviation, OFFSET_TOLERANCE, "counts"),
            ("sensitivity", check.sensitivity_deviation, SENSITIVITY_TOLERANCE, "counts/g"),
        ]
        for name, deviation, tolerance, unit in coefficients:
            for axis, value in zip(AXES, deviation or (), strict=False):
                if abs(value) > tolerance:
                    drift.append(
                        warning(
                            problem=f"{name} {axis} {value:+.2f} {unit} from its baseline at "
                            f"the latest check, beyond ± {tolerance:g}",
                            quantity=name,
                            axis=axis,
                            deviation=value,
                            tolerance=tolerance,
                        )
                    )
    return checks, drift


def _mean(triples: Sequence[Triple]) -> Triple:
    x, y, z = (sum(column) / len(triples) for column in zip(*triples, strict=True))
    return (x, y, z)


def _less(value: Triple, reference: Triple) -> Triple:
    x, y, z = (v - r for v, r in zip(value, reference, strict=True))
    return (x, y, z)
