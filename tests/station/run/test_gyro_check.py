"""The verification move on the unit's own calibrated output, over a real pty: it tells
gyros the station calibrated from gyros nobody did."""

import time
from collections.abc import Iterator

import numpy as np
import pytest

from station.device import DeviceCalibration, PutterDriver
from station.domain.signals.stillness import StillnessThresholds
from station.run.gyro_check import MoveOutcome, VerificationMove
from station.run.unit_output import UnitOutputCheck
from station.simulator.putter import VirtualPutter

SEED = 12


@pytest.fixture
def unit() -> Iterator[tuple[VirtualPutter, PutterDriver]]:
    with VirtualPutter(seed=SEED, serial="PT000012", speed=20.0, start_pose="verify_tilted") as p:
        url = p.serve_pty()
        with PutterDriver.open(url) as driver:
            yield p, driver


def verification_angle(putter: VirtualPutter, driver: PutterDriver) -> MoveOutcome:
    truth = putter.truth
    # The accelerometer calibrated with the truth: its frame is the body frame.
    driver.write_calibration(DeviceCalibration(truth.offset_counts, truth.matrix))
    driver.start_stream(calibrated=True)
    output = UnitOutputCheck(keep_streaming=True)
    while output.poll(driver) is None:
        time.sleep(0.01)
    move = VerificationMove(output.window, output.rest, StillnessThresholds(), 500.0, 30.0)
    putter.move_to("face_up", 1.5)
    while (outcome := move.poll(driver)) is None:
        time.sleep(0.01)
    return outcome


def test_the_unit_s_own_gyros_carry_gravity_only_once_calibrated(
    unit: tuple[VirtualPutter, PutterDriver],
) -> None:
    putter, driver = unit
    truth = putter.truth
    uncalibrated = verification_angle(putter, driver)
    driver.stop_stream()
    putter.move_to("verify_tilted", 1.5, wait=True)
    driver.drain_calibrated()  # what was still on the way when the stream stopped
    k = truth.gyro_matrix
    driver.write_gyro_calibration(DeviceCalibration(truth.gyro_bias_dps, np.linalg.inv(k)))
    calibrated = verification_angle(putter, driver)
    assert uncalibrated.angle_deg is not None
    assert calibrated.angle_deg is not None
    # K off by up to 1 % turns the 64° move by a few tenths of a degree; with K and the
    # bias written, what is left is noise and g-sensitivity (~0.05° at most).
    assert calibrated.angle_deg < 0.08
    assert uncalibrated.angle_deg > 0.25 > calibrated.angle_deg
