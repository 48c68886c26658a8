"""Typed contents of the command replies: who the unit is and what calibration it holds."""

from dataclasses import dataclass

import numpy as np

from station.device.protocol import (
    CALIBRATION_REPLY_STRUCT,
    CALIBRATION_STRUCT,
    IDENTITY_STRUCT,
    PROTOCOL_VERSION,
    TEXT_FIELD_BYTES,
    decode_text,
    encode_text,
)
from station.domain.arrays import FloatArray
from station.domain.sensors.sensor_spec import PUTTER_SENSOR, SensorSpec


@dataclass(frozen=True, slots=True)
class Identity:
    """The IDENTITY reply: serial number, firmware version, sensor part, protocol version."""

    serial: str
    firmware: str
    sensor_part: str
    protocol_version: int = PROTOCOL_VERSION

    def encode(self) -> bytes:
        """The IDENTITY payload."""
        return IDENTITY_STRUCT.pack(
            self.protocol_version,
            encode_text(self.serial, TEXT_FIELD_BYTES["serial"]),
            encode_text(self.firmware, TEXT_FIELD_BYTES["firmware"]),
            encode_text(self.sensor_part, TEXT_FIELD_BYTES["sensor_part"]),
        )

    @classmethod
    def decode(cls, payload: bytes) -> "Identity":
        """Parse an IDENTITY payload."""
        version, serial, firmware, part = IDENTITY_STRUCT.unpack(payload)
        return cls(decode_text(serial), decode_text(firmware), decode_text(part), version)


def _vector(value: FloatArray | list[float]) -> FloatArray:
    return np.asarray(value, dtype=np.float32).astype(np.float64)


@dataclass(frozen=True, eq=False)
class DeviceCalibration:
    """Calibration coefficients as the unit stores them (IEEE-754 float32).

    The unit turns counts into g with ``g = matrix @ (raw - offset)``: ``offset`` is
    3 counts, ``matrix`` 3-by-3 in g/count. The gyro coefficients have the same form
    (:meth:`gyro_default`): ``rate = matrix @ (measured - offset)`` with ``offset`` the
    gyro bias in deg/s and ``matrix`` the inverse of the gyro matrix K. Values are
    rounded to float32 on construction, so what is written compares exactly with what
    is read back. ``written`` is False while the unit still holds its factory defaults.
    """

    offset: FloatArray
    matrix: FloatArray
    written: bool = True

    def __post_init__(self) -> None:
        offset = _vector(self.offset)
        matrix = _vector(self.matrix)
        if offset.shape != (3,) or matrix.shape != (3, 3):
            raise ValueError(
                f"calibration needs 3 offsets and a 3x3 matrix, got {offset.shape} "
                f"and {matrix.shape}"
            )
        if not (np.isfinite(offset).all() and np.isfinite(matrix).all()):
            raise ValueError("calibration coefficients must be finite")
        object.__setattr__(self, "offset", offset)
        object.__setattr__(self, "matrix", matrix)

    def __eq__(self, other: object) -> bool:
        """Same coefficients, bit for bit (both are float32 values), and same flag."""
        if not isinstance(other, DeviceCalibration):
            return NotImplemented
        return (
            self.written == other.written
            and np.array_equal(self.offset, other.offset)
            and np.array_equal(self.matrix, other.matrix)
        )

    __hash__ = None  # type: ignore[assignment]

    @classmethod
    def factory_default(cls, sensor: SensorSpec = PUTTER_SENSOR) -> "DeviceCalibration":
        """What a fresh unit of ``sensor`` (the putter's by default) holds: its nominal
        zero g and sensitivity, not written."""
        return cls(
            np.full(3, sensor.zero_g_counts),
            np.eye(3) / sensor.counts_per_g,
            written=False,
        )

    @classmethod
    def gyro_default(cls) -> "DeviceCalibration":
        """The gyro coefficients of a fresh unit: no bias, unit matrix, not written."""
        return cls(np.zeros(3), np.eye(3), written=False)

    def apply(self, raw: FloatArray) -> FloatArray:
        """N-by-3 counts to N-by-3 g (or gyro deg/s to deg/s), as the unit does in
        calibrated mode."""
        return (np.asarray(raw, dtype=np.float64) - self.offset) @ self.matrix.T

    def encode(self) -> bytes:
        """The WRITE_CAL payload: 3 offsets then the matrix row by row."""
        return CALIBRATION_STRUCT.pack(*self.offset, *self.matrix.ravel())

    def encode_reply(self) -> bytes:
        """The CALIBRATION reply payload: written flag, then as :meth:`encode`."""
        return CALIBRATION_REPLY_STRUCT.pack(int(self.written), *self.offset, *self.matrix.ravel())

    @classmethod
    def decode(cls, payload: bytes) -> "DeviceCalibration":
        """Parse a WRITE_CAL payload (the unit's side)."""
        values = np.array(CALIBRATION_STRUCT.unpack(payload))
        return cls(values[:3], values[3:].reshape(3, 3))

    @classmethod
    def decode_reply(cls, payload: bytes) -> "DeviceCalibration":
        """Parse a CALIBRATION reply payload."""
        written, *rest = CALIBRATION_REPLY_STRUCT.unpack(payload)
        values = np.array(rest)
        return cls(values[:3], values[3:].reshape(3, 3), written=bool(written))
