"""The virtual putter's command handling: each command frame in, its reply frame out."""

from collections.abc import Callable
from typing import Final

from station.device.messages import DeviceCalibration, Identity
from station.device.protocol import (
    MAX_CALIBRATED_RATE_HZ,
    MAX_ERROR_TEXT,
    PAYLOAD_LENGTHS,
    RATE_STRUCT,
    ErrorCode,
    Frame,
    FrameType,
    StreamMode,
    encode_frame,
)
from station.domain.constants import MAX_RATE_HZ
from station.simulator.stream import SampleStream

_COMMANDS: Final = frozenset(
    {
        FrameType.IDENTIFY,
        FrameType.START_STREAM,
        FrameType.STOP_STREAM,
        FrameType.SET_RATE,
        FrameType.WRITE_CAL,
        FrameType.READ_CAL,
        FrameType.WRITE_GYRO_CAL,
        FrameType.READ_GYRO_CAL,
    }
)


class _RefusedError(Exception):
    """A command the firmware answers with an error reply."""

    def __init__(self, code: ErrorCode, text: str) -> None:
        super().__init__(text)
        self.code = code
        self.text = text


def _coefficients(payload: bytes) -> DeviceCalibration:
    """The coefficients of a WRITE_CAL or WRITE_GYRO_CAL payload; non-finite ones refused."""
    try:
        return DeviceCalibration.decode(payload)
    except ValueError:
        raise _RefusedError(ErrorCode.BAD_VALUE, "coefficients not finite") from None


class Firmware:
    """The unit's command interpreter, as ``docs/protocol.md`` specifies it.

    ``identity`` says who the unit claims to be at the time of asking (a fault can
    change its serial number); ``calibration`` and ``gyro_calibration`` (bias and
    K⁻¹, applied to the gyros of the calibrated stream) are what its flash holds, from
    ``factory`` on (default: the putter's nominal, :meth:`DeviceCalibration.factory_default`).
    """

    def __init__(
        self,
        stream: SampleStream,
        identity: Callable[[], Identity],
        factory: DeviceCalibration | None = None,
    ) -> None:
        self.stream = stream
        self.identity = identity
        self.calibration = factory or DeviceCalibration.factory_default()
        self.gyro_calibration = DeviceCalibration.gyro_default()

    def answer(self, frame: Frame) -> bytes:
        """The reply frame to ``frame``: its result, an ACK or an error reply."""
        kind = frame.type
        try:
            return self._execute(kind, frame.payload)
        except _RefusedError as refusal:
            payload = bytes((kind, refusal.code)) + refusal.text.encode("ascii")[:MAX_ERROR_TEXT]
            return encode_frame(FrameType.ERROR, payload)

    def _execute(self, kind: int, payload: bytes) -> bytes:
        if kind not in _COMMANDS:
            raise _RefusedError(ErrorCode.UNKNOWN_COMMAND, f"unknown command 0x{kind:02x}")
        low, high = PAYLOAD_LENGTHS[kind]
        if not low <= len(payload) <= high:
            raise _RefusedError(ErrorCode.BAD_LENGTH, f"payload of {len(payload)} B")
        if kind == FrameType.IDENTIFY:
            return encode_frame(FrameType.IDENTITY, self.identity().encode())
        if kind == FrameType.READ_CAL:
            return encode_frame(FrameType.CALIBRATION, self.calibration.encode_reply())
        if kind == FrameType.READ_GYRO_CAL:
            return encode_frame(FrameType.GYRO_CALIBRATION, self.gyro_calibration.encode_reply())
        if kind == FrameType.START_STREAM:
            self._start(payload[0])
        elif kind == FrameType.STOP_STREAM:
            self.stream.mode = None
        elif kind == FrameType.SET_RATE:
            self._set_rate(RATE_STRUCT.unpack(payload)[0])
        elif kind == FrameType.WRITE_CAL:
            self.calibration = _coefficients(payload)
        elif kind == FrameType.WRITE_GYRO_CAL:
            self.gyro_calibration = _coefficients(payload)
        return encode_frame(FrameType.ACK, bytes((kind,)))

    def _start(self, mode: int) -> None:
        if mode not in (StreamMode.RAW, StreamMode.CALIBRATED):
            raise _RefusedError(ErrorCode.BAD_VALUE, f"stream mode {mode}")
        if mode == StreamMode.CALIBRATED and self.stream.rate_hz > MAX_CALIBRATED_RATE_HZ:
            raise _RefusedError(ErrorCode.BAD_VALUE, "rate too high for calibrated")
        self.stream.start(StreamMode(mode))

    def _set_rate(self, rate: int) -> None:
        if not 1 <= rate <= MAX_RATE_HZ:
            raise _RefusedError(ErrorCode.BAD_VALUE, f"rate {rate} not in 1..1000")
        if self.stream.mode == StreamMode.CALIBRATED and rate > MAX_CALIBRATED_RATE_HZ:
            raise _RefusedError(ErrorCode.BAD_VALUE, "rate too high for calibrated")
        self.stream.rate_hz = rate
        self.stream.restart_timing()
