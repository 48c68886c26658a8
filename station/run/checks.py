"""The limit checks of one unit's run, taken at its verdict.

Every pose's noise and link loss, the solved offsets and sensitivities, the verification
pose's calibrated |g| and the gyro biases, each against the limits profile
(:func:`station.limits.check`). Kept apart from :class:`station.session.UnitRun`, which
drives the run, so the checks read as one list; :mod:`station.run.verdict` adds them to
the failures found on the way.
"""

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from station.calibration import Calibration, apply
from station.journal import Capture
from station.limits import LimitsProfile, check
from station.records import FailureReason, GyroSummary
from station.sensor import AXES


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
    """Check the poses taken, the solved ``calibration`` and the ``gyro`` summary."""
    reasons: list[FailureReason | None] = []
    for i, capture in sorted(captures.items()):
        for axis, std in zip(AXES, capture.record.std.as_tuple(), strict=True):
            reasons.append(check(profile, "pose_noise", std, axis=axis, pose=i))
        reasons.append(check(profile, "link_loss", capture.loss_fraction, pose=i))
    error = None
    if calibration is not None:
        for i, axis in enumerate(AXES):
            reasons.append(check(profile, "offset", float(calibration.offset[i]), axis=axis))
        for i, axis in enumerate(AXES):
            value = float(calibration.sensitivity[i])
            reasons.append(check(profile, "sensitivity", value, axis=axis))
        if fit_count in captures:
            raw = np.array(captures[fit_count].record.mean.as_tuple())
            error = abs(float(np.linalg.norm(apply(calibration, raw))) - 1.0) * 1000.0
            reasons.append(check(profile, "verification_error", error, pose=fit_count))
    if gyro is not None:
        for axis, bias in zip(AXES, gyro.bias.as_tuple(), strict=True):
            reasons.append(check(profile, "gyro_bias", bias, axis=axis))
    return CheckResult([r for r in reasons if r is not None], error)
