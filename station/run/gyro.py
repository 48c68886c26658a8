"""The gyro matrix of a whole-unit run: fitted from the moves, checked, written, recorded.

Model ([Tedaldi2014]_, ``docs/calibration.md``): the gyros read ``m = b + K·ω``, ω the
true rate in the calibrated accelerometer's frame. The bias b is the gyros' mean over
every still pose captured; K comes from :func:`station.domain.gyro.motion.fit_gyro_matrix` over the
moves :class:`~station.run.gyro_moves.MoveRecorder` kept between the captures, each
with the gravity directions the solved accelerometer calibration gives its two poses.

When a [Park2014]_ g-sensitivity fit is known for the unit, its scale-factor term at
the specific force of each sample (about ±600 ppm at 1 g) is taken out of the rates
first (:func:`station.domain.gyro.compensate`, with that term alone), so that K holds only
what does not depend on the orientation.

The unit then holds b and K⁻¹ (``docs/protocol.md``) and turns its gyro readings into
``K⁻¹·(m − b)`` on its calibrated stream.
"""

from collections.abc import Mapping
from typing import get_args

import numpy as np

from station.device import DeviceCalibration, PutterDriver
from station.domain.arrays import FloatArray
from station.domain.calibration import Calibration, Solution, apply
from station.domain.gyro import GyroErrorModel, compensate
from station.domain.gyro.motion import GyroMatrixFit, Move, fit_gyro_matrix
from station.domain.i18n import tr
from station.domain.product.limits import LimitsProfile, check
from station.domain.product.run_settings import RunSettings
from station.domain.record.records import (
    FailureReason,
    GyroMatrixRecord,
    GyroMove,
    Vector3,
)
from station.domain.sensors.record_bounds import CONDITION_MAX
from station.domain.sensors.sensor import Axis
from station.results.journal import Capture
from station.run.gyro_check import VerificationMove
from station.run.gyro_moves import MoveRecorder, RecordedMove
from station.run.operator_text import pose_words
from station.run.unit_output import UnitOutputCheck
from station.run.verdict import verification_move_failed

AXES: tuple[Axis, ...] = get_args(Axis)


def _unit(vectors: FloatArray) -> FloatArray:
    return np.asarray(vectors / np.linalg.norm(vectors, axis=-1, keepdims=True))


class LiveGyro:
    """The moves of one run, the gyro matrix once fitted, and the verification move.

    ``g_sensitivity`` is the scale-factor-form g-sensitivity ``N`` (3×3, 1/g) of a stored
    [Park2014]_ fit of the unit, or None.
    """

    def __init__(
        self, rate_hz: float, settings: RunSettings, g_sensitivity: FloatArray | None = None
    ) -> None:
        self.recorder = MoveRecorder(rate_hz)
        self.g_sensitivity = g_sensitivity
        self.fit: GyroMatrixFit | None = None
        self._rate_hz = rate_hz
        self._settings = settings
        self._verification: VerificationMove | None = None
        #: The unit's own calibrated gyros over the verification move, degrees.
        self.verification_deg: float | None = None
        #: Why the verification move gave no angle.
        self.failure: FailureReason | None = None

    def coefficients(
        self, captures: Mapping[int, Capture], solution: Solution
    ) -> DeviceCalibration:
        """What the unit is to hold: the bias over the still poses and K⁻¹.

        K is fitted once (a rewrite after a reconnection keeps it);
        :class:`station.domain.gyro.motion.GyroMatrixError` when the moves cannot determine it.
        """
        if self.fit is None:
            means = [c.record.gyro_mean for c in captures.values()]
            bias = np.mean([m.as_tuple() for m in means if m is not None], axis=0)
            self.fit_matrix(solution.calibration, bias)
        assert self.fit is not None
        self._verification = None
        inverse = np.asarray(np.linalg.inv(self.fit.scale_matrix), dtype=np.float64)
        return DeviceCalibration(self.fit.bias_dps, inverse)

    @property
    def verifying(self) -> bool:
        """Whether the verification move is under way."""
        return self._verification is not None

    def start_verification(self, output: UnitOutputCheck) -> str:
        """Start the verification move from the unit's still window; what to tell the operator."""
        settings = self._settings
        self._verification = VerificationMove(
            output.window,
            output.rest,
            settings.stillness,
            self._rate_hz,
            settings.pose_timeout_s,
        )
        return tr(
            "verification move: turn the putter {pose} and hold it still",
            pose=pose_words(settings.gyro_verification_pose),
        )

    def poll_verification(self, driver: PutterDriver) -> bool:
        """Take in the calibrated samples; True once the verification move is judged."""
        assert self._verification is not None
        outcome = self._verification.poll(driver)
        if outcome is None:
            return False
        self._verification = None
        self.verification_deg = outcome.angle_deg
        if outcome.problem is not None:
            self.failure = verification_move_failed(outcome.problem)
        return True

    def fit_matrix(self, calibration: Calibration, bias_dps: FloatArray) -> GyroMatrixFit:
        """Fit K to the recorded moves; :class:`station.domain.gyro.motion.GyroMatrixError` when
        they cannot determine it."""
        usable = [m for m in self.recorder.moves if m.unusable is None]
        moves = [self._move(m, calibration, bias_dps) for m in usable]
        self.fit = fit_gyro_matrix(moves, bias_dps)
        return self.fit

    def _move(self, move: RecordedMove, calibration: Calibration, bias: FloatArray) -> Move:
        ends = _unit(apply(calibration, np.array([move.mean_before, move.mean_after])))
        rates = move.gyro_dps
        if self.g_sensitivity is not None and len(rates):
            term = GyroErrorModel(bias, np.eye(3), np.zeros((3, 3)), self.g_sensitivity)
            rates = bias + compensate(term, rates, apply(calibration, move.accel_counts))
        return Move(self.recorder.times(move), rates, ends[0], ends[1])

    def checks(self, profile: LimitsProfile) -> list[FailureReason]:
        """The verification move against the profile (and a verification move that could
        not be judged); K's scale errors and misalignments are judged with their U among
        the run's limit checks (:func:`station.domain.product.judging.limit_checks`)."""
        if self.fit is None:
            return []
        found: list[FailureReason | None] = []
        if self.verification_deg is not None:
            found.append(check(profile, "gyro_verification", self.verification_deg))
        found.append(self.failure)
        return [f for f in found if f is not None]

    def record(self) -> GyroMatrixRecord | None:
        """The fit as the run stores it (None before the fit)."""
        fit = self.fit
        if fit is None:
            return None
        recorded = self.recorder.moves
        usable = [i for i, m in enumerate(recorded) if m.unusable is None]
        residual = {usable[j]: float(r) for j, r in zip(fit.used, fit.residual_deg, strict=True)}
        left_out = {usable[u.index]: u.reason for u in fit.unusable}
        moves = tuple(
            GyroMove(
                before=m.before,
                after=m.after,
                residual_deg=residual.get(i),
                unusable=m.unusable or left_out.get(i),
            )
            for i, m in enumerate(recorded)
        )
        errors = fit.standard_errors
        return GyroMatrixRecord(
            matrix=_rows(fit.scale_matrix),
            standard_errors=None if errors is None else _rows(errors),
            bias_dps=Vector3(x=fit.bias_dps[0], y=fit.bias_dps[1], z=fit.bias_dps[2]),
            moves=moves,
            residual_rms_deg=fit.residual_rms_deg,
            condition_number=min(max(1.0, fit.condition_number), CONDITION_MAX),
            g_sensitivity_removed=self.g_sensitivity is not None,
            verification_deg=self.verification_deg,
        )


def _rows(matrix: FloatArray) -> tuple[tuple[float, float, float], ...]:
    return tuple((float(r[0]), float(r[1]), float(r[2])) for r in matrix)
