"""Screening refusals: values, spacing and coverage of the poses."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.calibration import (
    CalibrationError,
    CoplanarPosesError,
    DuplicatePoseError,
    InvalidValueError,
    RailValueError,
    coverage,
    pair_angles_deg,
    solve,
)
from station.calibration.synthetic import random_directions, six_directions
from tests.station.calibration.test_paper import TABLE_2

NOMINAL = 2048.0 + 819.2 * six_directions()


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_refuses_non_finite_values_naming_the_pose(bad: float) -> None:
    poses = TABLE_2.copy()
    poses[3, 1] = bad
    with pytest.raises(InvalidValueError, match="pose 4: y is not a finite number") as info:
        solve(poses)
    assert info.value.pose == 3


@pytest.mark.parametrize(("value", "axis"), [(0.0, 0), (4095.0, 2), (4100.0, 1)])
def test_refuses_values_at_the_adc_rails(value: float, axis: int) -> None:
    poses = TABLE_2.copy()
    poses[1, axis] = value
    with pytest.raises(RailValueError, match=f"pose 2: {'xyz'[axis]} is at the ADC rail") as info:
        solve(poses)
    assert info.value.pose == 1


def test_refuses_a_duplicate_pose_naming_both() -> None:
    poses = TABLE_2.copy()
    poses[5] = poses[2] + [3.0, -2.0, 1.0]
    with pytest.raises(DuplicatePoseError, match="pose 6 repeats pose 3") as info:
        solve(poses)
    assert info.value.pose == 5


def test_refuses_coplanar_poses() -> None:
    t = np.radians([0, 60, 120, 180, 240, 300, 30, 90, 150])
    v = np.column_stack([np.cos(t), np.sin(t), np.zeros_like(t)])  # all in the x-y plane
    with pytest.raises(CoplanarPosesError, match="near one plane"):
        solve(2048 + 819.2 * v, "nine")


def test_refuses_a_wrongly_shaped_array() -> None:
    with pytest.raises(CalibrationError, match="N×3"):
        solve(np.zeros((7, 2)))


def test_six_axis_poses_have_full_coverage_and_right_angles() -> None:
    assert coverage(NOMINAL) == pytest.approx(1.0)
    angles = pair_angles_deg(NOMINAL)
    assert angles[0, 1] == pytest.approx(180.0)
    assert angles[0, 2] == pytest.approx(90.0)


@settings(max_examples=50)
@given(seed=st.integers(0, 2**32 - 1), offset=st.floats(-300, 300))
def test_spacing_and_coverage_ignore_the_offset(seed: int, offset: float) -> None:
    directions = random_directions(np.random.default_rng(seed), 8)
    poses = 2048.0 + 819.2 * directions
    np.testing.assert_allclose(pair_angles_deg(poses + offset), pair_angles_deg(poses), atol=1e-9)
    assert coverage(poses + offset) == pytest.approx(coverage(poses), abs=1e-9)
    cos = np.clip(directions @ directions.T, -1, 1)
    np.testing.assert_allclose(pair_angles_deg(poses), np.degrees(np.arccos(cos)), atol=1e-5)


@settings(max_examples=300, deadline=None)
@given(
    poses=st.lists(
        st.tuples(*[st.floats(1.0, 4094.0) | st.floats(allow_nan=False)] * 3),
        min_size=6,
        max_size=12,
    ),
    model=st.sampled_from(["six", "nine"]),
)
def test_any_poses_give_a_calibration_or_a_refusal(
    poses: list[tuple[float, float, float]], model: str
) -> None:
    try:
        solution = solve(np.array(poses), model)  # type: ignore[arg-type]
    except CalibrationError as exc:
        message = str(exc)
    else:
        assert np.all(np.isfinite(solution.calibration.matrix))
        assert np.all(solution.calibration.sensitivity > 0)
        return
    assert message
    assert "\n" not in message
