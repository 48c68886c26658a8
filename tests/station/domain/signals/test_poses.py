"""The named putter poses."""

import itertools

import numpy as np
import pytest

from station.domain.signals.orientation import angle_deg
from station.domain.signals.poses import (
    CALIBRATION_POSES,
    CORNER_SIGNS,
    POSES,
    VERIFICATION_POSE,
    pose,
)


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
    assert len(POSES) == len(CALIBRATION_POSES) + 1 + len(CORNER_SIGNS)
    assert set(CALIBRATION_POSES) | {VERIFICATION_POSE} <= set(POSES)
    assert all(p.instruction for p in POSES.values())


@pytest.mark.parametrize("signs", CORNER_SIGNS, ids=str)
def test_a_corner_pose_is_named_by_the_parts_that_point_up(signs: tuple[int, int, int]) -> None:
    corners = [p for p in POSES.values() if "corner cradle" in p.instruction]
    diagonal = np.array(signs) / np.sqrt(3)
    (corner,) = [p for p in corners if np.allclose(p.gravity_body, diagonal)]
    words = corner.name.split("_")
    assert words[0] == ("toe" if signs[0] > 0 else "heel")
    assert words[1] == ("face" if signs[1] > 0 else "back")
    assert words[2] == ("grip" if signs[2] > 0 else "head")
    assert angle_deg(corner.gravity_body, pose(VERIFICATION_POSE).gravity_body) > 60


def test_an_unknown_pose_names_the_known_ones() -> None:
    with pytest.raises(KeyError, match="unknown pose 'sideways'; known: shaft_up"):
        pose("sideways")
