"""Hypothesis strategies: true units and pose sets with known truth."""

import numpy as np
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from station.domain.sensors.sensor import NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G
from station.simulator.sensor import SensorTruth

offsets = st.floats(NOMINAL_OFFSET_COUNTS - 207, NOMINAL_OFFSET_COUNTS + 207)
sensitivities = st.floats(
    NOMINAL_SENSITIVITY_COUNTS_PER_G * 0.95, NOMINAL_SENSITIVITY_COUNTS_PER_G * 1.05
)


@st.composite
def true_units(draw: st.DrawFn, cross_axis: float = 0.0) -> SensorTruth:
    """A unit within the datasheet spreads; off-diagonal coupling uniform in ±cross_axis."""
    offset = np.array([draw(offsets) for _ in range(3)])
    s = np.array([draw(sensitivities) for _ in range(3)])
    coupling = np.zeros((3, 3))
    if cross_axis > 0:
        for i, j in [(0, 1), (0, 2), (1, 0), (1, 2), (2, 0), (2, 1)]:
            coupling[i, j] = draw(st.floats(-cross_axis, cross_axis))
    return SensorTruth.accelerometer(offset, np.diag(s) @ (np.eye(3) + coupling))


@st.composite
def rotations(draw: st.DrawFn) -> Rotation:
    """Any rotation (from a non-degenerate quaternion)."""
    q = np.array([draw(st.floats(-1, 1)) for _ in range(4)])
    if np.linalg.norm(q) < 0.1:
        q = np.array([0.0, 0.0, 0.0, 1.0])
    return Rotation.from_quat(q)


seeds = st.integers(0, 2**32 - 1)
