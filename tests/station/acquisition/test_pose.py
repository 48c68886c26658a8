"""Taking poses from the virtual putter over a real pty, faults included."""

import time
from collections.abc import Iterator

import numpy as np
import pytest

from station.acquisition import (
    LinkQualityError,
    NotStillError,
    PoseAcquisition,
    SaturatedAxisError,
    StillnessThresholds,
    acquire_pose,
)
from station.device import DeviceDisconnectedError, DeviceTimeoutError, PutterDriver
from station.poses import CALIBRATION_POSES, VERIFICATION_POSE, pose
from station.simulator import VirtualPutter

SPEED = 25.0


@pytest.fixture
def unit() -> Iterator[VirtualPutter]:
    with VirtualPutter(seed=5, speed=SPEED) as putter:
        putter.serve_pty()
        yield putter


@pytest.fixture
def driver(unit: VirtualPutter) -> Iterator[PutterDriver]:
    assert unit.url is not None
    with PutterDriver.open(unit.url) as drv:
        drv.start_stream()
        yield drv


def reading(unit: VirtualPutter, name: str) -> np.ndarray:
    truth = unit.truth
    force = pose(name).gravity_body
    return truth.offset_counts + truth.sensitivity_counts_per_g * (truth.cross_axis @ force)


def poll_until_done(acquisition: PoseAcquisition) -> None:
    while acquisition.poll() is None:
        time.sleep(0.005)


def test_a_whole_unit_of_seven_poses_matches_the_truth(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    for name in (*CALIBRATION_POSES, VERIFICATION_POSE):
        moved_at = unit.move_to(name)
        assert moved_at is not None
        result = acquire_pose(driver, pose=name, timeout_s=20.0, from_seq=moved_at)
        assert result.first_seq > moved_at
        assert result.pose == name
        assert result.sample_count == 1024
        # The window starts after the move and its tremor: never before 1.5 s of handling.
        assert 1.5 < result.wait_s < 6.0
        assert result.duration_s == pytest.approx(1024 / 500)
        # Temperature drift (up to 0.5 count/°C) and noise: within a count of the truth.
        np.testing.assert_allclose(result.accel_mean, reading(unit, name), atol=1.0)
        assert np.all(result.accel_std < StillnessThresholds().accel_std_max_counts)
        np.testing.assert_allclose(result.gyro_mean, unit.truth.gyro_bias_dps, atol=0.03)
        assert 24.0 < result.temperature_c < 27.0
        assert result.link.samples_lost == 0
        assert result.to_dict()["link"]["loss_fraction"] == 0.0


def test_a_unit_that_never_settles_is_not_still(unit: VirtualPutter, driver: PutterDriver) -> None:
    unit.faults.never_settle = True
    unit.move_to("toe_up")
    with pytest.raises(NotStillError, match=r"pose toe_up: not still after 8 s: .*spread") as info:
        acquire_pose(driver, pose="toe_up", timeout_s=8.0)
    assert info.value.pose == "toe_up"


def test_a_saturated_axis_is_reported_as_such(unit: VirtualPutter, driver: PutterDriver) -> None:
    unit.faults.saturate_axis = "y"
    with pytest.raises(SaturatedAxisError, match="pose face_up: accelerometer y saturated") as info:
        acquire_pose(driver, pose="face_up", timeout_s=8.0)
    assert info.value.axes == ("y",)


def test_a_lossy_link_refuses_the_pose(unit: VirtualPutter, driver: PutterDriver) -> None:
    unit.faults.drop_rate = 0.04
    with pytest.raises(LinkQualityError, match=r"pose face_up: bad link after 5 s: link lost"):
        acquire_pose(driver, pose="face_up", timeout_s=5.0)


def test_a_slightly_lossy_link_still_gives_the_pose(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    unit.faults.drop_rate = 0.003
    result = acquire_pose(driver, pose="face_up", timeout_s=10.0)
    assert result.loss_fraction <= 0.01
    driver.wait_samples(3000, timeout=5.0)
    # About one sample in 330 goes missing, and the driver sees it.
    assert 0.0005 < driver.stats.loss_fraction < 0.01


def test_pulling_the_cable_during_a_pose_is_a_disconnection(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    moved_at = unit.move_to("shaft_up")
    assert moved_at is not None
    acquisition = PoseAcquisition(driver, pose="shaft_up", from_seq=moved_at)
    while acquisition.elapsed_s < 0.5:
        assert acquisition.poll() is None
        time.sleep(0.005)
    unit.unplug()
    with pytest.raises(DeviceDisconnectedError):
        poll_until_done(acquisition)


def test_a_stream_that_stops_is_a_timeout(unit: VirtualPutter, driver: PutterDriver) -> None:
    driver.stop_stream()
    driver.drain()
    acquisition = PoseAcquisition(driver, pose="face_up", stall_s=0.2)
    with pytest.raises(DeviceTimeoutError, match="no samples from"):
        poll_until_done(acquisition)
