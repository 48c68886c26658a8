"""Taking poses from the virtual putter over a real pty, faults included."""

import math
import time
from collections.abc import Iterator

import numpy as np
import pytest

from station.device import DeviceDisconnectedError, DeviceTimeoutError, PutterDriver
from station.domain.sensors.sensor import GYRO_DPS_PER_LSB, TEMP_C_PER_LSB
from station.domain.signals.poses import CALIBRATION_POSES, VERIFICATION_POSE, pose
from station.run.acquisition import (
    LinkQualityError,
    NotStillError,
    PoseAcquisition,
    SaturatedAxisError,
    StillnessThresholds,
    acquire_pose,
)
from station.simulator import VirtualPutter
from station.simulator.motion import Handling
from station.simulator.sensor import REFERENCE_TEMPERATURE_C

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


def reading(unit: VirtualPutter, name: str, temperature_c: float) -> np.ndarray:
    """The noise-free counts of pose ``name`` at ``temperature_c`` (the sensor model's)."""
    truth = unit.truth
    force = pose(name).gravity_body
    dt = temperature_c - REFERENCE_TEMPERATURE_C
    offset = truth.offset_counts + truth.offset_tempco_counts_per_c * dt
    sensitivity = truth.sensitivity_counts_per_g * (1 + truth.sensitivity_tempco_per_c * dt)
    return offset + sensitivity * (truth.cross_axis @ force)


def poll_until_done(acquisition: PoseAcquisition) -> None:
    while acquisition.poll() is None:
        time.sleep(0.005)


def first_still_window_ends_s(unit: VirtualPutter, move_s: float) -> tuple[float, float]:
    """Earliest and latest device time, from a move's start, of its first still window's end.

    The window (W seconds) may start only once the put-down tremor's rate no longer
    spreads a gyro beyond ``gyro_std_max_dps``: the binding check (the accelerometer's
    spread, drift and |g| pass the moment the unit is put down, by a factor of two or
    more). The rocking tremor's rate is ``A e^(−u/τ) sin(ωu + φ)`` about a random axis,
    ``A = θ₀ √(ω² + 1/τ²)``; from ``u₀`` on it holds ``E(u₀) = A²τ/4 (1 ± 1/√(1 + ω²τ²))
    e^(−2u₀/τ)`` (deg/s)²·s. A window starting ``u₀`` after the put-down therefore
    passes for sure once ``g_max² E(u₀)/W`` plus the noise's variance (its 1024-sample
    estimate 5 σ high) is under the limit², and cannot pass while a third of
    ``g_min² E(u₀)/W`` (the axis the rock projects most on), less the window mean's
    square (at most ``(2θ₀/W)²``), is over it. ``g`` spans the gyro's gain over
    directions (scale error and misalignment). The window ends on the detector's hop
    grid, counted from the move's first sample (the move starts within a sample before).
    """
    h = Handling()
    limits = StillnessThresholds()
    truth = unit.truth
    rate = 500.0
    window = limits.window_samples / rate
    tau = h.settle_time_constant_s
    omega = 2 * math.pi * h.tremor_rock_hz
    amplitude = h.tremor_rock_deg * math.hypot(omega, 1 / tau)
    ripple = 1 / math.sqrt(1 + (omega * tau) ** 2)
    gains = np.linalg.svd(
        np.eye(3) + truth.gyro_misalignment + np.diag(truth.gyro_scale_error),
        compute_uv=False,
    )
    limit = limits.gyro_std_max_dps**2
    noise = truth.gyro_noise_dps**2 * (1 + 5 * math.sqrt(2 / limits.window_samples))
    noise += GYRO_DPS_PER_LSB**2 / 12
    most = gains.max() ** 2 * amplitude**2 * tau / 4 * (1 + ripple) / window
    least = gains.min() ** 2 * amplitude**2 * tau / 4 * (1 - ripple) / window / 3
    mean_sq = (2 * h.tremor_rock_deg / window) ** 2
    latest_u = tau / 2 * math.log(most / (limit - noise))
    earliest_u = tau / 2 * math.log(least / (limit + mean_sq))
    hop = limits.hop_samples / rate
    return move_s + earliest_u + window - 1 / rate, move_s + latest_u + window + hop


def test_a_whole_unit_of_seven_poses_matches_the_truth(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    earliest, latest = first_still_window_ends_s(unit, move_s=1.5)
    for name in (*CALIBRATION_POSES, VERIFICATION_POSE):
        moved_at = unit.move_to(name, 1.5)
        assert moved_at is not None
        result = acquire_pose(driver, pose=name, timeout_s=20.0, from_seq=moved_at)
        assert result.first_seq > moved_at
        assert result.pose == name
        assert result.summary.count == 1024
        # The window starts once the put-down tremor has died down (device time).
        assert earliest <= result.wait_s <= latest
        assert result.duration_s == pytest.approx(1024 / 500)
        # The model at the window's temperature, within 5 σ of the mean of 1024 samples
        # of noise and rounding, plus the drift over half a step of the temperature.
        expected = reading(unit, name, result.summary.temperature_c)
        tempco = np.abs(
            reading(unit, name, REFERENCE_TEMPERATURE_C + 1)
            - reading(unit, name, REFERENCE_TEMPERATURE_C)
        )
        sigma = math.sqrt(unit.truth.noise_counts**2 + 1 / 12) / math.sqrt(1024)
        np.testing.assert_array_less(
            np.abs(result.summary.accel_mean - expected), 5 * sigma + tempco * TEMP_C_PER_LSB / 2
        )
        assert np.all(result.summary.accel_std < StillnessThresholds().accel_std_max_counts)
        np.testing.assert_allclose(result.summary.gyro_mean, unit.truth.gyro_bias_dps, atol=0.03)
        assert 24.0 < result.summary.temperature_c < 27.0
        assert result.link.lost_samples == 0
        assert result.link.loss_fraction == 0.0


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
