"""Screening refusals: values, spacing and coverage of the poses."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.domain.calibration import (
    BeyondDatasheetError,
    CalibrationError,
    CoplanarPosesError,
    DuplicatePoseError,
    IllConditionedError,
    InvalidValueError,
    NotCountsError,
    RailValueError,
    coverage,
    pair_angles_deg,
    solve,
)
from station.domain.calibration.geometry import GeometryLimits, screen
from station.simulator.recording import random_directions, six_directions, spread_directions
from tests.conftest import examples
from tests.station.domain.calibration.test_paper import TABLE_2

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


@settings(max_examples=examples(300), deadline=None)
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


def test_values_in_g_are_named_as_such_not_as_saturated() -> None:
    directions = random_directions(np.random.default_rng(1), 12)
    for scale in (1.0, 9.80665):  # g, m/s²
        with pytest.raises(NotCountsError, match="look like acceleration in g or m/s²"):
            solve(scale * directions)


def test_a_pose_beyond_the_datasheet_is_named_as_the_cause() -> None:
    # Seven poses: inconsistent, too few to leave one out; the pose no KXM52 could read
    # (1352 counts from 2048 at 1 g) is the cause named. With twelve it is left out.
    directions = spread_directions(12)
    poses = 2048.0 + 819.2 * directions
    poses[6, 0] = 3400.0
    seven = 2048.0 + 819.2 * spread_directions(7)
    seven[6, 0] = 3400.0
    with pytest.raises(BeyondDatasheetError, match="pose 7: x reads beyond the datasheet") as info:
        solve(seven)
    assert info.value.pose == 6
    assert solve(poses).excluded == (6,)


def test_an_out_of_spec_unit_still_calibrates_with_six_poses() -> None:
    # The station then fails it on its offset and sensitivity limits, with the values.
    poses = 2300.0 + 1000.0 * six_directions()
    np.testing.assert_allclose(solve(poses).calibration.offset, 2300.0)


def test_degenerate_geometry_is_named_not_blamed_on_stillness() -> None:
    # Six poses in one hemisphere: eq. 10 gives a negative k here, which used to read "a
    # pose was not still"; the cause is the geometry (cond(J) 1556 at the nominal sensor).
    poses = np.array(
        [
            [2651.5, 1405.1, 1838.0],
            [2795.2, 1599.8, 2115.3],
            [2574.7, 1738.0, 1419.4],
            [1705.9, 2572.9, 1643.2],
            [2558.7, 2012.7, 1382.2],
            [2686.4, 2452.2, 2055.8],
        ]
    )
    with pytest.raises(IllConditionedError, match="pose geometry degenerate"):
        solve(poses)


def test_an_unidentifiable_nine_parameter_set_is_named_not_unconverged() -> None:
    # Poses only along the axes say nothing about the cross-axis terms.
    axes = np.vstack([np.eye(3), -np.eye(3)])
    poses = 2048.0 + 819.2 * np.vstack([axes, axes])
    poses += np.random.default_rng(3).normal(0.0, 0.05, poses.shape)
    with pytest.raises(IllConditionedError, match="cross-axis terms need them"):
        solve(poses, "nine")


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(12, 60))
def test_near_duplicates_are_reported_not_refused_by_least_squares(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    directions = random_directions(rng, n)
    directions[1] = directions[0] + 0.02 * rng.standard_normal(3)  # ~1° apart
    directions[1] /= np.linalg.norm(directions[1])
    poses = 2048.0 + 819.2 * directions + rng.normal(0.0, 0.05, (n, 3))
    try:
        quality = solve(poses, "nine").quality
    except (CoplanarPosesError, IllConditionedError):  # random sets may lack coverage
        return
    assert quality.near_duplicates >= 2
    assert quality.min_angle_deg < 10.0


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(33, 120), repeats=st.integers(0, 20))
def test_the_closest_poses_of_many_match_all_pairs(seed: int, n: int, repeats: int) -> None:
    # Beyond 32 poses a k-d tree (over the distinct poses) stands in for all pairs.
    rng = np.random.default_rng(seed)
    poses = 2048.0 + 819.2 * random_directions(rng, n)
    poses[rng.integers(0, n, repeats)] = poses[0]  # exact repeats, the tree's worst case
    result = screen(poses[None], GeometryLimits(), refuse_duplicates=False)
    angles = pair_angles_deg(poses)
    np.fill_diagonal(angles, np.inf)
    assert float(result.min_angle_deg[0]) == pytest.approx(angles.min(), abs=1e-6)
    assert int(result.near[0]) == int((angles.min(axis=1) < 10.0).sum())


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(7, 40), close=st.floats(0.001, 30.0))
def test_near_duplicates_agree_with_the_closest_angle_whatever_is_refused(
    seed: int, n: int, close: float
) -> None:
    # A solve that refuses no duplicates (least squares on a stream, min_angle_deg 0)
    # counts them against the same 10° as any other: never "0 near-duplicates" beside a
    # closest pair 0.018° apart.
    rng = np.random.default_rng(seed)
    directions = random_directions(rng, n)
    turn = np.cross(directions[0], rng.standard_normal(3))
    turn /= np.linalg.norm(turn)
    angle = np.radians(close)
    directions[1] = np.cos(angle) * directions[0] + np.sin(angle) * turn
    poses = 2048.0 + 819.2 * directions
    result = screen(poses[None], GeometryLimits(min_angle_deg=0.0), refuse_duplicates=False)
    angles = pair_angles_deg(poses)
    np.fill_diagonal(angles, np.inf)
    assert int(result.near[0]) == int((angles.min(axis=1) < 10.0).sum())
    assert (int(result.near[0]) == 0) == (float(result.min_angle_deg[0]) >= 10.0)
