"""Least-squares 6- and 9-parameter fits against units with known truth."""

import numpy as np
import pytest
from hypothesis import given, settings

from station.domain.calibration import (
    TooFewPosesError,
    apply,
    solve,
    solve_least_squares,
    solve_paper,
)
from station.simulator.recording import (
    pose_means,
    random_directions,
    six_directions,
    spread_directions,
)
from station.simulator.sensor import SensorTruth
from tests.station.domain.calibration.strategies import rotations, seeds, true_units
from tests.station.domain.calibration.test_paper import TABLE_2


def g_error_mg(unit, calibration, rng) -> np.ndarray:  # type: ignore[no-untyped-def]
    """|calibrated |g| − 1| in mg over 2000 random orientations of the true unit."""
    raw = unit.still_counts(random_directions(rng, 2000))
    return np.asarray(np.abs(np.linalg.norm(apply(calibration, raw), axis=1) - 1.0) * 1000.0)


def test_with_six_poses_it_agrees_with_the_paper() -> None:
    ls = solve_least_squares(TABLE_2, "six")
    paper = solve_paper(TABLE_2)
    np.testing.assert_allclose(ls.calibration.offset, paper.calibration.offset, atol=1e-8)
    np.testing.assert_allclose(ls.calibration.sensitivity, paper.calibration.sensitivity, atol=1e-8)
    assert ls.standard_errors is None  # no redundancy, no standard errors


@settings(max_examples=40, deadline=None)
@given(unit=true_units(), rotation=rotations(), seed=seeds)
def test_six_model_recovers_truth_from_redundant_poses(unit, rotation, seed) -> None:  # type: ignore[no-untyped-def]
    # 12 well-spread poses in any orientation, 0.05 counts noise per pose mean.
    rng = np.random.default_rng(seed)
    poses = pose_means(unit, rotation.apply(spread_directions(12)), 0.05, rng)
    solution = solve(poses, "six")
    assert solution.method == "least-squares"
    np.testing.assert_allclose(solution.calibration.offset, unit.offset_counts, atol=0.5)
    np.testing.assert_allclose(
        solution.calibration.sensitivity, unit.sensitivity_counts_per_g, rtol=5e-4
    )


@settings(max_examples=30, deadline=None)
@given(unit=true_units(cross_axis=0.02), rotation=rotations(), seed=seeds)
def test_nine_model_recovers_cross_axis_units(unit, rotation, seed) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(seed)
    poses = pose_means(unit, rotation.apply(spread_directions(18)), 0.05, rng)
    cal = solve(poses, "nine").calibration
    assert np.allclose(np.tril(cal.matrix, -1), 0.0)  # upper-triangular
    np.testing.assert_allclose(cal.offset, unit.offset_counts, atol=0.5)
    assert g_error_mg(unit, cal, rng).max() < 1.0
    # C is S⁻¹ up to a rotation: CᵀC = S⁻ᵀS⁻¹.
    s_inv = np.linalg.inv(unit.counts_per_g)
    metric, true_metric = cal.matrix.T @ cal.matrix, s_inv.T @ s_inv
    assert np.abs(metric - true_metric).max() < 2e-3 * np.abs(true_metric).max()


def test_nine_model_beats_six_on_two_percent_cross_axis() -> None:
    # The acceptance: 18 poses, 2 % coupling: nine < 1 mg where six leaves ~10 mg.
    rng = np.random.default_rng(11)
    worst_nine, typical_six = [], []
    for _ in range(10):
        unit = SensorTruth.draw_accelerometer(rng, cross_axis=0.02)
        poses = pose_means(unit, spread_directions(18), 0.05, rng)
        worst_nine.append(g_error_mg(unit, solve(poses, "nine").calibration, rng).max())
        typical_six.append(g_error_mg(unit, solve(poses, "six").calibration, rng).max())
    assert max(worst_nine) < 1.0
    assert np.median(typical_six) > 5.0


def test_standard_errors_match_the_scatter_of_repeated_fits() -> None:
    rng = np.random.default_rng(5)
    unit = SensorTruth.draw_accelerometer(rng)
    directions = spread_directions(10)
    fits = [solve(pose_means(unit, directions, 0.3, rng), "six") for _ in range(300)]
    scatter = np.std([f.calibration.offset for f in fits], axis=0)
    reported = np.mean([f.standard_errors.offset for f in fits if f.standard_errors], axis=0)
    np.testing.assert_allclose(reported, scatter, rtol=0.25)


def test_quality_reports_residuals_of_a_bad_pose() -> None:
    rng = np.random.default_rng(8)
    unit = SensorTruth.draw_accelerometer(rng)
    directions = spread_directions(12)
    poses = pose_means(unit, directions, 0.02, rng)
    poses[4] += 60.0 * directions[4]  # one pose taken while moving: ~70 mg along gravity
    q = solve_least_squares(poses, "six").quality  # the plain fit; solve() leaves pose 4 out
    assert q.residual_max_mg > 10.0
    assert int(np.argmax(np.abs(q.pose_g - 1.0))) == 4


@pytest.mark.parametrize(("model", "n"), [("six", 5), ("nine", 8)])
def test_refuses_too_few_poses(model: str, n: int) -> None:
    poses = pose_means(
        SensorTruth.draw_accelerometer(np.random.default_rng(1)),
        spread_directions(n),
        0.0,
        np.random.default_rng(2),
    )
    with pytest.raises(TooFewPosesError, match=f"{n} poses given, this model needs at least"):
        solve(poses, model)  # type: ignore[arg-type]


def test_six_pose_jig_tilt_does_not_matter() -> None:
    rng = np.random.default_rng(4)
    unit = SensorTruth.draw_accelerometer(rng)
    poses = pose_means(unit, six_directions(rng, tilt_deg=10.0), 0.0, rng)
    cal = solve(poses).calibration
    np.testing.assert_allclose(cal.offset, unit.offset_counts, atol=1e-6)
    np.testing.assert_allclose(cal.sensitivity, unit.sensitivity_counts_per_g, rtol=1e-9)
