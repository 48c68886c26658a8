"""Reading what the unit holds before the run (as-found), writing the solved
coefficients into it and reading them back (as-left).

The unit stops streaming, takes the coefficients into its flash and hands them back;
the station compares the two (:func:`readback_difference`) against the limits profile's
``writeback`` limit. A whole-unit run also writes the gyro coefficients (the bias and
K⁻¹, ``docs/protocol.md``) and reads them back the same way. A device error on the way
propagates: the caller fails the unit.
"""

from datetime import UTC, datetime

import numpy as np

from station.device import DeviceCalibration, PutterDriver
from station.domain.calibration import Calibration
from station.domain.record.records import AsFound, StoredCoefficients


def stored(calibration: DeviceCalibration) -> StoredCoefficients:
    """The record of one set of coefficients as the unit stores them."""
    offset, matrix = calibration.offset.tolist(), calibration.matrix.tolist()
    return StoredCoefficients.model_validate(
        {"written": calibration.written, "offset": offset, "matrix": matrix}
    )


def read_as_found(driver: PutterDriver, *, gyro: bool) -> AsFound:
    """The coefficients the unit holds now (its gyros' too if ``gyro``), read between a
    stop and a fresh start of its raw stream: the as-found values of ISO/IEC 17025:2017
    7.8.4.1, taken before the run writes any.

    Raises :class:`station.device.DeviceError` when the unit does not answer.
    """
    read_at = datetime.now(UTC)
    driver.stop_stream()
    accelerometer = stored(driver.read_calibration())
    gyros = stored(driver.read_gyro_calibration()) if gyro else None
    driver.start_stream()
    return AsFound(read_at=read_at, accelerometer=accelerometer, gyro=gyros)


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
