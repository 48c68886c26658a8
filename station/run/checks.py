"""The limit checks of one unit's run, taken at its verdict.

Every pose's noise and link loss, the solved offsets and sensitivities, the verification
pose's calibrated |g| and the gyro biases, each against the limits profile
(:func:`station.domain.judging.limit_checks`, which the report's re-judging uses too). Kept
apart from :class:`station.run.unit_run.UnitRun`, which drives the run, so the checks read as
one list; :mod:`station.run.verdict` adds them to the failures found on the way.
"""

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from station.domain.calibration import Calibration, apply
from station.domain.judging import Measured, Triple, limit_checks
from station.domain.limits import LimitsProfile
from station.domain.records import FailureReason, GyroSummary
from station.results.journal import Capture


@dataclass(frozen=True)
class CheckResult:
    """The failed checks, and the verification pose's error (mg) when it was taken."""

    reasons: list[FailureReason]
    verification_error_mg: float | None


def run_checks(
    profile: LimitsProfile,
    captures: Mapping[int, Capture],
    calibration: Calibration | None,
    fit_count: int,
    gyro: GyroSummary | None,
) -> CheckResult:
    """Check the poses taken, the solved ``calibration`` and the ``gyro`` summary
    (:func:`station.domain.judging.limit_checks` on what they measured)."""
    error = None
    if calibration is not None and fit_count in captures:
        raw = np.array(captures[fit_count].record.mean.as_tuple())
        error = abs(float(np.linalg.norm(apply(calibration, raw))) - 1.0) * 1000.0
    measured = Measured(
        pose_noise={i: c.record.std.as_tuple() for i, c in captures.items()},
        link_loss={i: c.loss_fraction for i, c in captures.items()},
        offset=_triple(calibration.offset) if calibration is not None else None,
        sensitivity=_triple(calibration.sensitivity) if calibration is not None else None,
        verification=None if error is None else (fit_count, error),
        gyro_bias=None if gyro is None else gyro.bias.as_tuple(),
    )
    return CheckResult(limit_checks(profile, measured), error)


def _triple(values: Any) -> Triple:
    return (float(values[0]), float(values[1]), float(values[2]))
