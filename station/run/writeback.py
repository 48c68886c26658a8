"""Writing the solved coefficients into the unit, and reading them back.

The unit stops streaming, takes the coefficients into its flash and hands them back;
the station compares the two (:func:`readback_difference`) against the limits profile's
``writeback`` limit. A whole-unit run also writes the gyro coefficients (the bias and
K⁻¹, ``docs/protocol.md``) and reads them back the same way. A device error on the way
propagates: the caller fails the unit.
"""

import numpy as np

from station.device import DeviceCalibration, PutterDriver
from station.domain.calibration import Calibration


def readback_difference(written: DeviceCalibration, back: DeviceCalibration) -> float:
    """The largest difference between written and read-back values, relative to each."""
    scale = np.concatenate([np.abs(written.offset), np.abs(written.matrix).ravel()])
    diff = np.concatenate([back.offset - written.offset, (back.matrix - written.matrix).ravel()])
    return float(np.max(np.abs(diff) / np.where(scale > 0, scale, 1.0)))


def write_and_read_back(
    driver: PutterDriver, calibration: Calibration, gyro: DeviceCalibration | None = None
) -> float:
    """Write ``calibration`` (and ``gyro``) into the unit and read them back: the largest
    relative difference.

    Raises :class:`station.device.DeviceError` when the unit does not take them.
    """
    written = DeviceCalibration(calibration.offset, calibration.matrix)
    driver.stop_stream()
    driver.write_calibration(written)
    difference = readback_difference(written, driver.read_calibration())
    if gyro is not None:
        driver.write_gyro_calibration(gyro)
        difference = max(difference, readback_difference(gyro, driver.read_gyro_calibration()))
    return difference
