"""Which pose the putter lies in, judged on what is known of its offsets [Song2006]."""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from station.domain.arrays import FloatArray
from station.domain.sensors.sensor import (
    NOMINAL_OFFSET_COUNTS,
    NOMINAL_SENSITIVITY_COUNTS_PER_G,
    OFFSET_SPREAD_COUNTS,
    SENSITIVITY_TOLERANCE,
)
from station.domain.signals.orientation import POSE_TOLERANCE_DEG, ZeroG, sense
from station.domain.signals.poses import POSES, Pose

AXIS_POSES = tuple(
    p for p in POSES.values() if np.count_nonzero(np.abs(p.gravity_body) > 1e-6) == 1
)

offsets = st.lists(
    st.floats(-OFFSET_SPREAD_COUNTS, OFFSET_SPREAD_COUNTS), min_size=3, max_size=3
).map(lambda v: NOMINAL_OFFSET_COUNTS + np.array(v))
sensitivities = st.lists(
    st.floats(-SENSITIVITY_TOLERANCE, SENSITIVITY_TOLERANCE), min_size=3, max_size=3
).map(lambda v: NOMINAL_SENSITIVITY_COUNTS_PER_G * (1 + np.array(v)))
axis_poses = st.sampled_from(AXIS_POSES)


def reading(pose: Pose, offset: FloatArray, sensitivity: FloatArray) -> FloatArray:
    """Noise-free mean counts of a unit lying exactly in ``pose`` (no cross-axis)."""
    return offset + sensitivity * pose.gravity_body


def test_the_six_axis_poses_are_found() -> None:
    assert len(AXIS_POSES) == 6


@given(axis_poses, offsets, sensitivities)
def test_any_unit_within_the_datasheet_is_taken_in_the_axis_pose_it_lies_in(
    pose: Pose, offset: FloatArray, sensitivity: FloatArray
) -> None:
    sensed = sense(reading(pose, offset, sensitivity))
    assert sensed.matches(pose, tolerance_deg=0.01)


two_axis_poses = st.lists(axis_poses, min_size=2, max_size=2, unique=True)


@given(two_axis_poses, offsets, sensitivities)
def test_a_unit_in_another_axis_pose_is_refused_whatever_its_offsets(
    poses: list[Pose], offset: FloatArray, sensitivity: FloatArray
) -> None:
    target, lying = poses
    assert not sense(reading(lying, offset, sensitivity)).matches(target, POSE_TOLERANCE_DEG)


@given(st.lists(axis_poses, min_size=1, max_size=6, unique=True), offsets, sensitivities)
def test_the_level_axes_of_the_poses_taken_read_their_offsets(
    taken: list[Pose], offset: FloatArray, sensitivity: FloatArray
) -> None:
    zero_g = ZeroG.measured((p, reading(p, offset, sensitivity)) for p in taken)
    level = np.any([np.abs(p.gravity_body) < 1e-6 for p in taken], axis=0)
    np.testing.assert_allclose(zero_g.offset[level], offset[level], rtol=0, atol=1e-9)
    np.testing.assert_array_equal(zero_g.doubt[level], 0.0)
    np.testing.assert_array_equal(zero_g.offset[~level], NOMINAL_OFFSET_COUNTS)
    np.testing.assert_array_equal(zero_g.doubt[~level], OFFSET_SPREAD_COUNTS)


def opposite(pose: Pose) -> Pose:
    return next(p for p in AXIS_POSES if np.allclose(p.gravity_body, -pose.gravity_body))


@given(axis_poses, st.booleans(), offsets, sensitivities)
def test_once_its_level_axes_are_measured_a_pose_reads_as_it_lies(
    first: Pose, flipped: bool, offset: FloatArray, sensitivity: FloatArray
) -> None:
    # A pose and its opposite share their level axes: after the one, the other's reading
    # is judged on measured offsets, not blurred by the datasheet's.
    target = opposite(first) if flipped else first
    zero_g = ZeroG.measured([(first, reading(first, offset, sensitivity))])
    sensed = sense(reading(target, offset, sensitivity), zero_g=zero_g)
    assert sensed.nearest is target
    assert sensed.nearest_deg < 1e-3
