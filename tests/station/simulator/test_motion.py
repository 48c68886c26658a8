"""The motion model: moves, handling accelerations and settling tremor."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from station.domain.signals.poses import POSES, pose
from station.simulator.motion import MotionModel


def model(start: str = "face_up", seed: int = 0) -> MotionModel:
    return MotionModel(pose(start).rotation, np.random.default_rng(seed))


@pytest.mark.parametrize("name", sorted(POSES))
def test_at_rest_the_unit_senses_one_g_along_the_pose_gravity(name: str) -> None:
    kin = model(name).evaluate(np.linspace(0, 5, 50))
    np.testing.assert_allclose(kin.force_g, np.tile(pose(name).gravity_body, (50, 1)), atol=1e-12)
    np.testing.assert_array_equal(kin.rate_dps, 0.0)


@pytest.mark.parametrize(
    ("start", "target"), [("face_up", "toe_down"), ("shaft_up", "verify_tilted")]
)
def test_integrating_the_body_rate_ends_at_the_target(start: str, target: str) -> None:
    motion = model(start)
    motion.move_to(pose(target).rotation, now=1.0, duration=1.5)
    dt = 1e-3
    t = np.arange(1.0, 2.5, dt) + dt / 2
    rates = np.radians(motion.evaluate(t).rate_dps)
    orientation = pose(start).rotation
    for w in rates:
        orientation = orientation * Rotation.from_rotvec(w * dt)
    error = (orientation.inv() * pose(target).rotation).magnitude()
    assert np.degrees(error) < 0.05


def test_handling_shows_in_the_accelerometer_and_the_tremor_dies_down() -> None:
    motion = model("face_up", seed=3)
    motion.move_to(pose("shaft_down").rotation, now=0.0, duration=1.5)
    during = motion.evaluate(np.linspace(0.05, 1.45, 300))
    assert np.abs(np.linalg.norm(during.force_g, axis=1) - 1).max() > 0.05
    assert np.linalg.norm(during.rate_dps, axis=1).max() > 100
    just_down = motion.evaluate(np.linspace(1.5, 1.7, 200))
    assert np.linalg.norm(just_down.rate_dps, axis=1).max() > 1.0
    t = np.linspace(motion.settled_at(), motion.settled_at() + 2, 500)
    settled = motion.evaluate(t)
    np.testing.assert_allclose(
        settled.force_g, np.tile(pose("shaft_down").gravity_body, (500, 1)), atol=5e-4
    )
    assert np.abs(settled.rate_dps).max() < 0.1


def test_a_unit_that_never_settles_keeps_shaking() -> None:
    motion = model()
    motion.never_settles = True
    motion.move_to(pose("toe_up").rotation, now=0.0, duration=1.0)
    late = motion.evaluate(np.linspace(60.0, 62.0, 1000))
    assert np.linalg.norm(late.force_g, axis=1).std() > 0.005
    assert np.abs(late.rate_dps).max() > 2.0


def test_a_move_needs_a_positive_time() -> None:
    with pytest.raises(ValueError, match="positive time"):
        model().move_to(pose("toe_up").rotation, now=0.0, duration=0.0)


@pytest.mark.parametrize("seed", [0, 7])
def test_a_move_queued_for_later_is_the_move_made_then(seed: int) -> None:
    # Queued at once, or made when its time comes: the unit senses the same, sample for
    # sample, before the second move (the first runs and settles) and after it.
    first, second = pose("shaft_down").rotation, pose("toe_up").rotation
    before, after = np.arange(0.0, 3.0, 0.002), np.arange(3.0, 6.0, 0.002)
    queued = model(seed=seed)
    queued.move_to(first, now=0.0, duration=1.0)
    queued.move_to(second, now=3.0, duration=1.0)
    made = model(seed=seed)
    made.move_to(first, now=0.0, duration=1.0)
    made_before = made.evaluate(before)
    made.move_to(second, now=3.0, duration=1.0)
    made_after = made.evaluate(after)
    for got, want in ((queued.evaluate(before), made_before), (queued.evaluate(after), made_after)):
        np.testing.assert_array_equal(got.force_g, want.force_g)
        np.testing.assert_array_equal(got.rate_dps, want.rate_dps)
    # The first move really ran: put down shaft down, then taken to toe up.
    np.testing.assert_allclose(made_before.force_g[-1], pose("shaft_down").gravity_body, atol=1e-3)
    np.testing.assert_allclose(made_after.force_g[-1], pose("toe_up").gravity_body, atol=1e-3)


def test_a_move_made_before_a_queued_one_replaces_it() -> None:
    motion = model()
    motion.move_to(pose("toe_up").rotation, now=0.0, duration=1.0)
    motion.move_to(pose("face_down").rotation, now=5.0, duration=1.0)
    motion.move_to(pose("shaft_up").rotation, now=2.0, duration=1.0)
    late = motion.evaluate(np.linspace(8.0, 9.0, 10))
    np.testing.assert_allclose(
        late.force_g, np.tile(pose("shaft_up").gravity_body, (10, 1)), atol=1e-3
    )


def test_a_move_queued_before_the_moves_kept_starts_from_where_they_started() -> None:
    # The samples drawn past the first move let the model forget the still start; a move
    # then queued before that first move begins from where it began.
    motion = model("face_up")
    motion.move_to(pose("toe_up").rotation, now=1.0, duration=1.0)
    motion.evaluate(np.linspace(0.0, 4.0, 100))
    motion.move_to(pose("face_down").rotation, now=5.0, duration=1.0)
    motion.move_to(pose("shaft_up").rotation, now=0.5, duration=1.0)
    late = motion.evaluate(np.linspace(8.0, 9.0, 10))
    np.testing.assert_allclose(
        late.force_g, np.tile(pose("shaft_up").gravity_body, (10, 1)), atol=1e-3
    )
