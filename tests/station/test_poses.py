"""The named putter poses."""

import itertools

import numpy as np
import pytest

from station.poses import CALIBRATION_POSES, POSES, VERIFICATION_POSE, pose


def test_the_six_calibration_poses_put_gravity_on_each_axis_both_ways() -> None:
    vectors = np.array([pose(name).gravity_body for name in CALIBRATION_POSES])
    np.testing.assert_allclose(np.abs(vectors).sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(vectors.sum(axis=0), 0.0, atol=1e-12)
    for a, b in itertools.combinations(vectors, 2):
        assert not np.allclose(a, b)


def test_the_verification_pose_aligns_no_axis_with_gravity() -> None:
    vector = pose(VERIFICATION_POSE).gravity_body
    assert np.linalg.norm(vector) == pytest.approx(1.0)
    assert np.abs(vector).max() < 0.8
    assert np.abs(vector).min() > 0.3


def test_every_pose_tells_the_operator_what_to_do() -> None:
    assert set(CALIBRATION_POSES) | {VERIFICATION_POSE} == set(POSES)
    assert all(p.instruction for p in POSES.values())


def test_an_unknown_pose_names_the_known_ones() -> None:
    with pytest.raises(KeyError, match="unknown pose 'sideways'; known: shaft_up"):
        pose("sideways")
