"""The verification move: the unit's own calibrated gyros against the gravity change.

Once a whole-unit run has written its coefficients, the unit streams calibrated samples
(acceleration in g, rates ``K⁻¹·(m − b)`` in deg/s). It lies in the verification pose:
:class:`~station.run.unit_output.UnitOutputCheck`'s window gives gravity's direction
there, ``u_start``. The operator then turns it into the run's
``gyro_verification_pose``; :class:`VerificationMove` waits for a still window at the
end (``u_end``), integrates the unit's rates over the move on SO(3)
(:func:`station.domain.gyro.motion.integrate_rates`) into R, from the body at the end to the
body at the start, and answers the angle between ``R·u_end`` and ``u_start`` in
degrees ([Tedaldi2014]_'s residual, on the unit's own output). With K and b right it is
noise (~0.02°); a gyro 1 % off turns it by about 1 % of the move.
"""

from dataclasses import dataclass
from typing import Final

import numpy as np

from station.device import PutterDriver
from station.domain.gyro.motion import Move, integrate_rates
from station.domain.signals.samples import SampleBlock
from station.domain.signals.stillness import StillnessThresholds, judge_window
from station.run.unit_output import CalibratedSamples

#: Samples of the still window that ends the move (half a second at 500 samples/s).
END_WINDOW: Final = 256
#: A rate above this (deg/s) means the operator has started the move.
MOVING_DPS: Final = 10.0


@dataclass(frozen=True)
class MoveOutcome:
    """The verification move's angle (degrees), or why it has none."""

    angle_deg: float | None
    problem: str | None = None


class VerificationMove:
    """The calibrated samples since the start window, until the unit lies still again."""

    def __init__(
        self,
        start: SampleBlock,
        rest: SampleBlock,
        stillness: StillnessThresholds,
        rate_hz: float,
        timeout_s: float,
    ) -> None:
        mean = start.summary().accel_mean
        self._u_start = mean / np.linalg.norm(mean)
        self._samples = CalibratedSamples(SampleBlock.concat((start[-1:], rest)))
        self._stillness = stillness.model_copy(update={"window_samples": END_WINDOW})
        self._rate_hz = rate_hz
        self._timeout_samples = int(timeout_s * rate_hz)
        self._moved = False

    def poll(self, driver: PutterDriver) -> MoveOutcome | None:
        """The outcome once the unit lies still after the move; None until then."""
        samples = self._samples.drain(driver)
        if not self._moved:
            self._moved = bool((np.linalg.norm(samples.gyro, axis=1) > MOVING_DPS).any())
        if self._moved and len(samples) > END_WINDOW and self._still(samples[-END_WINDOW:]):
            driver.stop_stream()
            return self._angle(samples)
        if len(samples) > self._timeout_samples:
            driver.stop_stream()
            seconds = self._timeout_samples / self._rate_hz
            problem = f"the unit did not lie still after a move within {seconds:g} s"
            return MoveOutcome(None, problem)
        return None

    def _still(self, window: SampleBlock) -> bool:
        """The station's one stillness judge, on the calibrated window read as the sensor's
        nominal counts (the judge's thresholds are in its counts)."""
        sensor = self._stillness.sensor
        counts = SampleBlock(window.rows.copy())
        counts.accel[:] = sensor.zero_g_counts + sensor.counts_per_g * window.accel
        return judge_window(counts, self._stillness).still

    def _angle(self, samples: SampleBlock) -> MoveOutcome:
        end = samples[-END_WINDOW:]
        mean = end.summary().accel_mean
        u_end = mean / np.linalg.norm(mean)
        span = samples[samples.seq <= end.seq[0]]
        move = Move(span.seq / self._rate_hz, span.gyro, self._u_start, u_end)
        if (problem := move.problem()) is not None:
            return MoveOutcome(None, f"samples of the move cannot be integrated: {problem}")
        rotation = integrate_rates(move.t, np.radians(move.rates_dps))
        cos = float(np.clip(rotation.apply(u_end) @ self._u_start, -1.0, 1.0))
        return MoveOutcome(float(np.degrees(np.arccos(cos))))
