"""A move between two still poses, and whether its samples can be integrated.

A move is the stretch of a stream from the last sample of one still pose to the first
sample of the next ([Tedaldi2014]_): its sample times, its raw gyro rates and the
gravity directions of the two poses in the calibrated accelerometer's frame. Its
samples must be evenly spaced: a step in ``t`` more than :data:`GAP_FACTOR` times the
move's median step (a lost sample doubles it), or a step that does not go forward,
makes it unusable, since the rotation over the gap is unknown.
"""

from dataclasses import dataclass
from typing import Final

import numpy as np

from station.domain.arrays import FloatArray

#: A step longer than this many median steps is a gap (one lost sample makes it 2).
GAP_FACTOR: Final = 1.5
#: A move needs at least this many samples to integrate.
MIN_MOVE_SAMPLES: Final = 2


@dataclass(frozen=True, eq=False)
class Move:
    """The samples of one move and the gravity directions at its two ends.

    Attributes:
        t: shape (n,), sample times, s.
        rates_dps: shape (n, 3), raw gyro rates (bias and K not removed), deg/s.
        gravity_before: shape (3,), unit vector of the still pose before the move,
            in the calibrated accelerometer's frame.
        gravity_after: shape (3,), the same for the still pose after it.
    """

    t: FloatArray
    rates_dps: FloatArray
    gravity_before: FloatArray
    gravity_after: FloatArray

    @property
    def gravity_turn_deg(self) -> float:
        """The angle between the gravity directions at the move's two ends, degrees."""
        cosine = np.clip(self.gravity_before @ self.gravity_after, -1, 1)
        return float(np.degrees(np.arccos(cosine)))

    def problem(self) -> str | None:
        """Why the move cannot be integrated, or None when it can."""
        n = len(self.t)
        if n < MIN_MOVE_SAMPLES or self.rates_dps.shape != (n, 3):
            return f"{n} samples, a move needs {MIN_MOVE_SAMPLES} with 3 rates each"
        if not (np.isfinite(self.t).all() and np.isfinite(self.rates_dps).all()):
            return "a sample is not a finite number"
        step = np.diff(self.t)
        if (step <= 0).any():
            k = int(np.argmax(step <= 0))
            return f"time does not increase at sample {k + 1} (t = {self.t[k + 1]:.6g} s)"
        median = float(np.median(step))
        if (step > GAP_FACTOR * median).any():
            k = int(np.argmax(step))
            return (
                f"gap of {step[k]:.4g} s at t = {self.t[k]:.6g} s "
                f"({step[k] / median:.1f} sample steps)"
            )
        return None
