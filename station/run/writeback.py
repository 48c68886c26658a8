"""Writing the solved coefficients into the unit, and reading them back.

The unit stops streaming, takes the coefficients into its flash and hands them back;
the station compares the two (:func:`readback_difference`) against the limits profile's
``writeback`` limit. A device error on the way propagates: the caller fails the unit.
"""

import numpy as np

from station.calibration import Calibration
from station.device import DeviceCalibration, PutterDriver


def readback_difference(written: DeviceCalibration, back: DeviceCalibration) -> float:
    """The largest difference between written and read-back values, relative to each."""
    scale = np.concatenate([np.abs(written.offset), np.abs(written.matrix).ravel()])
    diff = np.concatenate([back.offset - written.offset, (back.matrix - written.matrix).ravel()])
    return float(np.max(np.abs(diff) / np.where(scale > 0, scale, 1.0)))


def write_and_read_back(driver: PutterDriver, calibration: Calibration) -> float:
    """Write ``calibration`` into the unit and read it back: their relative difference.

    Raises :class:`station.device.DeviceError` when the unit does not take it.
    """
    written = DeviceCalibration(calibration.offset, calibration.matrix)
    driver.stop_stream()
    driver.write_calibration(written)
    back = driver.read_calibration()
    return readback_difference(written, back)
