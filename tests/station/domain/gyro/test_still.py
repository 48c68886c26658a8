"""The station's still poses: gyro bias, noise and the bias-vs-gravity slope."""

import numpy as np
import pytest

from station.domain.errors import InputError
from station.domain.gyro.still import GyroStillSummary, summarize_still_poses

#: The six still poses of the station: gravity along ±x, ±y, ±z, slightly tilted.
SIX_POSES = np.array(
    [[1, 0.05, 0], [-1, 0, 0.04], [0.03, 1, 0], [0, -1, 0.06], [0.02, 0, 1], [0, 0.05, -1]],
    dtype=float,
)
BIAS = np.array([0.02, -0.015, 0.01])
NOISE = 0.002  # deg/s, scatter of the pose means (bias repeatability)


def _means(slope: np.ndarray, seed: int, poses: np.ndarray = SIX_POSES) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return BIAS + poses @ slope.T + rng.normal(0.0, NOISE, (poses.shape[0], 3))


def test_no_slope_is_found_consistent_with_zero() -> None:
    consistent = 0
    for seed in range(20):
        summary = summarize_still_poses(
            _means(np.zeros((3, 3)), seed), np.full((6, 3), 0.05), SIX_POSES
        )
        consistent += sum(bool(a.slope_consistent_with_zero) for a in summary.axes)
    assert consistent >= 55  # α = 0.01 on 60 tests: a few false alarms at most


def test_a_bias_form_slope_is_found_and_measured() -> None:
    slope = np.zeros((3, 3))
    slope[0, 1] = 0.05  # deg/s/g, 25 × the pose scatter
    summary = summarize_still_poses(_means(slope, 3), np.full((6, 3), 0.05), SIX_POSES)
    x = summary.axes[0]
    assert x.slope_consistent_with_zero is False
    assert x.slope_dps_per_g is not None
    assert x.slope_stderr_dps_per_g is not None
    assert x.slope_dps_per_g[1] == pytest.approx(0.05, abs=5 * x.slope_stderr_dps_per_g[1])
    assert x.bias_dps == pytest.approx(float(np.mean(_means(slope, 3)[:, 0])), rel=1e-12)


def test_noise_is_the_rms_of_the_pose_noise() -> None:
    noise = np.tile([[0.03], [0.04]], (3, 3))
    summary = summarize_still_poses(_means(np.zeros((3, 3)), 0), noise, SIX_POSES)
    assert summary.axes[1].noise_dps == pytest.approx(np.sqrt((0.03**2 + 0.04**2) / 2))


def test_four_poses_give_a_slope_but_no_test() -> None:
    poses = SIX_POSES[[0, 2, 4, 5]]
    summary = summarize_still_poses(_means(np.zeros((3, 3)), 1, poses), np.zeros((4, 3)), poses)
    assert summary.axes[0].slope_dps_per_g is not None
    assert summary.axes[0].slope_consistent_with_zero is None
    assert "at least 5 poses" in (summary.axes[0].reason or "")


def test_poses_in_one_plane_give_no_slope() -> None:
    poses = SIX_POSES.copy()
    poses[:, 2] = 0.0
    summary = summarize_still_poses(_means(np.zeros((3, 3)), 1, poses), np.zeros((6, 3)), poses)
    assert summary.axes[2].slope_dps_per_g is None
    assert "do not span three dimensions" in (summary.axes[2].reason or "")
    assert summary.axes[2].bias_dps == pytest.approx(
        float(np.mean(_means(np.zeros((3, 3)), 1, poses)[:, 2]))
    )


def test_summary_round_trips_through_a_dict() -> None:
    summary = summarize_still_poses(_means(np.zeros((3, 3)), 2), np.full((6, 3), 0.05), SIX_POSES)
    data = summary.to_dict()
    assert set(data) == {"poses", "alpha", "bias_limit_dps", "axes"}
    assert set(data["axes"][0]) >= {"axis", "bias_dps", "noise_dps", "slope_dps_per_g"}
    assert GyroStillSummary.from_dict(data) == summary


@pytest.mark.parametrize(
    ("means", "noise", "gravity", "message"),
    [
        (np.zeros((6, 2)), np.zeros((6, 3)), SIX_POSES, "gyro means: expected an N-by-3"),
        (np.zeros((6, 3)), np.zeros((5, 3)), SIX_POSES, "pose noise: expected an 6-by-3"),
        (np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), "no poses"),
        (np.zeros((6, 3)), -np.ones((6, 3)), SIX_POSES, "pose noise: pose 0: negative"),
        (
            np.zeros((6, 3)),
            np.zeros((6, 3)),
            np.where(np.arange(18).reshape(6, 3) == 7, np.nan, SIX_POSES),
            "gravity: pose 2: value is not finite",
        ),
    ],
)
def test_bad_inputs_are_named(
    means: np.ndarray, noise: np.ndarray, gravity: np.ndarray, message: str
) -> None:
    with pytest.raises(InputError, match=message):
        summarize_still_poses(means, noise, gravity)


def test_bias_is_checked_against_the_limit() -> None:
    means = _means(np.zeros((3, 3)), 4)
    summary = summarize_still_poses(means, np.zeros((6, 3)), SIX_POSES, bias_limit_dps=0.0175)
    assert [a.bias_within_limit for a in summary.axes] == [False, True, True]  # 0.02, -0.015, 0.01
    unlimited = summarize_still_poses(means, np.zeros((6, 3)), SIX_POSES)
    assert [a.bias_within_limit for a in unlimited.axes] == [None, None, None]
    with pytest.raises(InputError, match="bias limit: must be positive"):
        summarize_still_poses(means, np.zeros((6, 3)), SIX_POSES, bias_limit_dps=0.0)
