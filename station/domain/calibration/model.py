"""The calibration itself and how it turns raw counts into acceleration.

A calibration maps raw accelerometer counts to acceleration in g (brief eq. 5 inverted)::

    g = C · (raw − o)

``o`` (3,) is the offset in counts, ``C`` (3×3) maps counts to g. The paper's
6-parameter model has ``C = diag(1/s_x, 1/s_y, 1/s_z)`` with ``s`` the sensitivity in
counts/g; the 9-parameter model has ``C`` upper-triangular, which adds the three
non-orthogonality (cross-axis) terms.
"""

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from station.domain.arrays import FloatArray

Model = Literal["six", "nine"]


@dataclass(frozen=True, eq=False)
class Calibration:
    """Offsets (counts) and the counts-to-g matrix of one accelerometer.

    Attributes:
        model: ``"six"`` (diagonal matrix) or ``"nine"`` (upper-triangular matrix).
        offset: shape (3,), the zero-g output of each axis, counts.
        matrix: shape (3, 3), maps counts to g: ``g = matrix @ (raw - offset)``.
    """

    model: Model
    offset: FloatArray
    matrix: FloatArray

    @property
    def sensitivity(self) -> FloatArray:
        """Shape (3,), counts/g of each axis along itself: ``1 / diag(matrix)``."""
        return np.asarray(1.0 / np.diag(self.matrix), dtype=np.float64)

    @classmethod
    def from_sensitivity(cls, offset: ArrayLike, sensitivity: ArrayLike) -> "Calibration":
        """The 6-parameter calibration with ``matrix = diag(1/sensitivity)``."""
        s = np.asarray(sensitivity, dtype=np.float64)
        return cls("six", np.asarray(offset, dtype=np.float64), np.diag(1.0 / s))

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: offset and sensitivity as ``{x, y, z}``, matrix as nested lists."""
        return {
            "model": self.model,
            "offset": xyz(self.offset),
            "sensitivity": xyz(self.sensitivity),
            "matrix": self.matrix.tolist(),
        }


def apply(calibration: Calibration, raw: ArrayLike) -> FloatArray:
    """Acceleration in g of raw counts: ``g = C · (raw − o)`` (eq. 5 inverted).

    Args:
        calibration: the unit's calibration.
        raw: shape (N, 3) or (3,), accelerometer counts.

    Returns:
        The same shape as ``raw``, acceleration in g.
    """
    counts = np.asarray(raw, dtype=np.float64)
    return np.asarray((counts - calibration.offset) @ calibration.matrix.T, dtype=np.float64)


def xyz(values: FloatArray) -> dict[str, float]:
    """Three values in axis order as the JSON's ``{x, y, z}``."""
    return {"x": float(values[0]), "y": float(values[1]), "z": float(values[2])}
