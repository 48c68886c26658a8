"""The classic ±1 g method ([Song2006]_ eqs. 2, 3): the baseline that needs a precise jig.

Each axis is held exactly along +1 g and −1 g; its offset and sensitivity are

    a_0 = (V(+1 g) + V(−1 g)) / 2        (eq. 2)
    s   = (V(+1 g) − V(−1 g)) / 2        (eq. 3)

using only that axis' own reading in its two poses. Any misalignment of the jig
enters the result directly: tilted by θ, the axis sees cos θ instead of 1 g.
"""

import numpy as np
from numpy.typing import ArrayLike

from station.domain.calibration.errors import CalibrationError, NonPositiveScaleError
from station.domain.calibration.model import Calibration


def solve_classic(plus: ArrayLike, minus: ArrayLike) -> Calibration:
    """Offsets and sensitivities from the six jig poses.

    Args:
        plus: shape (3, 3); row j is the mean counts (x, y, z) with axis j at +1 g.
        minus: shape (3, 3); row j is the mean counts with axis j at −1 g.
    """
    up = np.asarray(plus, dtype=np.float64)
    down = np.asarray(minus, dtype=np.float64)
    if up.shape != (3, 3) or down.shape != (3, 3):
        raise CalibrationError(
            f"the ±1 g method takes two 3×3 arrays, got {up.shape} and {down.shape}"
        )
    if not (np.all(np.isfinite(up)) and np.all(np.isfinite(down))):
        raise CalibrationError("the ±1 g poses hold a value that is not a finite number")
    v_plus, v_minus = np.diag(up), np.diag(down)
    sensitivity = (v_plus - v_minus) / 2.0
    if np.any(sensitivity <= 0):
        raise NonPositiveScaleError(
            "an axis reads less at +1 g than at −1 g: the poses are swapped"
        )
    return Calibration.from_sensitivity((v_plus + v_minus) / 2.0, sensitivity)
