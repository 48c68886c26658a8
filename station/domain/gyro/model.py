"""The gyro error model with g-sensitivity, and its regressors.

Per gyro axis i ∈ {x, y, z} the output (deg/s) is linear in its parameters::

    gyro_i = b_i + Σ_j S_ij·ω_j + Σ_j B_ij·a_j + (Σ_j N_ij·a_j)·ω_i

ω the applied rate (deg/s, N-by-3), a the specific force on the unit (g, N-by-3),
b the bias (deg/s), S the scale-factor/misalignment matrix (S = I + β of [Park2014]_
eq. 4: β_ii scale-factor error, β_ij misalignment), B the bias-form g-sensitivity
(deg/s/g) that public calibration tools model, and N the scale-factor-form
g-sensitivity (1/g; reported in ppm/g) of [Park2014]_ eq. 4, where G_ii·a_sense(i)·ω_i
is the row N_i· with a single non-zero entry on the sense axis.

.. [Park2014] B.-S. Park, "A Study on the G-Sensitivity Error of MEMS Vibratory
   Gyroscopes", 2014.
"""

from dataclasses import dataclass
from typing import Final

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.sensors.sensor import AXES

PPM: Final = 1e6
TERMS_PER_AXIS: Final = 10


def term_names(axis: int) -> list[str]:
    """Names of the ten terms of gyro ``axis`` (0, 1, 2), in regressor column order."""
    a = AXES[axis]
    return [f"bias_{a}"] + [f"{group}_{a}{b}" for group in ("S", "B", "N") for b in AXES]


def regressors(axis: int, rate: FloatArray, acc: FloatArray) -> FloatArray:
    """Regressor matrix (N-by-10) of gyro ``axis``: ``[1, ω, a, a·ω_axis]``.

    Columns follow :func:`term_names`; rate in deg/s, acceleration in g.
    """
    ones = np.ones((rate.shape[0], 1))
    return np.hstack([ones, rate, acc, acc * rate[:, axis : axis + 1]])


@dataclass(frozen=True)
class GyroErrorModel:
    """Coefficients of the error model (module docstring), all axes.

    ``bias`` (3,) deg/s; ``scale`` (3, 3); ``bias_g`` (3, 3) deg/s/g; ``n_g`` (3, 3)
    1/g. Row = gyro axis i, column = rate or acceleration axis j.
    """

    bias: FloatArray
    scale: FloatArray
    bias_g: FloatArray
    n_g: FloatArray

    def __post_init__(self) -> None:
        shapes = {"bias": (3,), "scale": (3, 3), "bias_g": (3, 3), "n_g": (3, 3)}
        for name, shape in shapes.items():
            value = np.asarray(getattr(self, name), dtype=np.float64)
            if value.shape != shape:
                raise ValueError(f"{name} must have shape {shape}, not {value.shape}")
            if not np.all(np.isfinite(value)):
                raise ValueError(f"{name} must be finite")
            object.__setattr__(self, name, value)

    @classmethod
    def ideal(cls) -> "GyroErrorModel":
        """A perfect gyro triad: no bias, unit scale, no g-sensitivity."""
        return cls(np.zeros(3), np.eye(3), np.zeros((3, 3)), np.zeros((3, 3)))

    def row(self, axis: int) -> FloatArray:
        """The ten coefficients of gyro ``axis`` in :func:`term_names` order."""
        return np.concatenate(
            [[self.bias[axis]], self.scale[axis], self.bias_g[axis], self.n_g[axis]]
        )

    def predict(self, rate: FloatArray, acc: FloatArray) -> FloatArray:
        """Gyro output (N-by-3, deg/s) for applied rate (deg/s) and specific force (g)."""
        rate = np.asarray(rate, dtype=np.float64)
        acc = np.asarray(acc, dtype=np.float64)
        return self.bias + rate @ self.scale.T + acc @ self.bias_g.T + (acc @ self.n_g.T) * rate
