"""Synthetic accelerometers and pose sets with known truth, for accuracy checks.

A true unit produces, for specific force g (in g, sensor frame), the counts

    a = o + S·g,

with o the offsets (counts) and S = diag(s)·(I + E) its counts-per-g matrix: s the
sensitivities, E the cross-axis coupling (zero diagonal). The exact calibration of
such a unit is C = S⁻¹; its 6-parameter part is diag(1/s) only when E = 0.
"""

from dataclasses import dataclass

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.sensor import (
    CROSS_AXIS_TYPICAL,
    NOMINAL_OFFSET_COUNTS,
    NOMINAL_SENSITIVITY_COUNTS_PER_G,
    OFFSET_SPREAD_COUNTS,
    SENSITIVITY_TOLERANCE,
)


@dataclass(frozen=True, eq=False)
class TrueUnit:
    """An accelerometer whose parameters are known exactly."""

    offset: FloatArray  # (3,) counts
    scale: FloatArray  # (3, 3) counts per g

    @property
    def sensitivity(self) -> FloatArray:
        """(3,) counts/g of each axis along itself."""
        return np.asarray(np.diag(self.scale), dtype=np.float64)

    def counts(self, g: FloatArray) -> FloatArray:
        """Noise-free counts (N, 3) for specific forces g (N, 3) in g."""
        return np.asarray(self.offset + g @ self.scale.T, dtype=np.float64)


def random_unit(
    rng: np.random.Generator,
    cross_axis: float = 0.0,
    offset_spread: float = OFFSET_SPREAD_COUNTS,
    sensitivity_tolerance: float = SENSITIVITY_TOLERANCE,
) -> TrueUnit:
    """A unit drawn uniformly within the datasheet spreads ([Song2006]_ Table 1).

    ``cross_axis``: each off-diagonal coupling is uniform in ±cross_axis (the KXM52's
    typical value is :data:`station.domain.sensor.CROSS_AXIS_TYPICAL`).
    """
    offset = NOMINAL_OFFSET_COUNTS + rng.uniform(-offset_spread, offset_spread, 3)
    s = NOMINAL_SENSITIVITY_COUNTS_PER_G * (
        1 + rng.uniform(-sensitivity_tolerance, sensitivity_tolerance, 3)
    )
    coupling = rng.uniform(-cross_axis, cross_axis, (3, 3))
    np.fill_diagonal(coupling, 0.0)
    return TrueUnit(offset=offset, scale=np.diag(s) @ (np.eye(3) + coupling))


def random_directions(rng: np.random.Generator, n: int) -> FloatArray:
    """n unit vectors drawn uniformly on the sphere, (n, 3)."""
    v = rng.standard_normal((n, 3))
    return np.asarray(v / np.linalg.norm(v, axis=1, keepdims=True), dtype=np.float64)


def spread_directions(n: int) -> FloatArray:
    """n unit vectors spread evenly over the sphere (Fibonacci lattice), (n, 3)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + np.sqrt(5.0)) * i
    r = np.sqrt(1.0 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def six_directions(rng: np.random.Generator | None = None, tilt_deg: float = 0.0) -> FloatArray:
    """The six ±1 g poses (+x, −x, +y, −y, +z, −z), each tilted by ``tilt_deg``.

    The tilt is applied about a random axis perpendicular to each direction (a jig
    misplaced by that angle); ``rng`` may be None only when ``tilt_deg`` is 0.
    """
    base = np.array(
        [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64
    )
    if tilt_deg == 0.0:
        return base
    if rng is None:
        raise ValueError("a tilt needs a random generator")
    theta = np.radians(tilt_deg)
    out = np.empty_like(base)
    for i, u in enumerate(base):
        w = rng.standard_normal(3)
        w -= (w @ u) * u
        w /= np.linalg.norm(w)
        out[i] = np.cos(theta) * u + np.sin(theta) * w
    return out


def pose_means(
    unit: TrueUnit, directions: FloatArray, noise_counts: float, rng: np.random.Generator
) -> FloatArray:
    """Mean counts of still poses with gravity along ``directions`` (N, 3).

    ``noise_counts`` is the standard deviation of each pose mean per axis (the sample
    noise divided by √(samples per pose)).
    """
    clean = unit.counts(directions)
    return np.asarray(clean + rng.normal(0.0, noise_counts, clean.shape), dtype=np.float64)


__all__ = [
    "CROSS_AXIS_TYPICAL",
    "TrueUnit",
    "pose_means",
    "random_directions",
    "random_unit",
    "six_directions",
    "spread_directions",
]
