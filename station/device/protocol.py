"""The putter's serial protocol, version 1: framing, CRC and payload codecs.

Version 1 with the gyro-coefficient extension (WRITE_GYRO_CAL, READ_GYRO_CAL,
GYRO_CALIBRATION): a unit without it answers UNKNOWN_COMMAND, and a station that does
not calibrate gyros never sends them, so either side may be older.

Every message in either direction is one frame (all integers little-endian except
the CRC)::

    A5 5A | type (u8) | length (u8) | payload (length bytes) | CRC-16 (u16, big-endian)

The CRC is CRC-16/CCITT-FALSE (polynomial 0x1021, initial value 0xFFFF) over type,
length and payload, computed by :func:`binascii.crc_hqx`. Each frame type has a fixed
payload length (the error reply a bounded one), so a corrupted header is refused
before its CRC is even looked at. ``docs/protocol.md`` is the reference for
firmware writers; this module is its executable form.
"""

import struct
from binascii import crc_hqx
from collections.abc import Mapping
from dataclasses import dataclass
from enum import IntEnum
from typing import Final

import numpy as np

from station.domain.sensors.sensor import GYRO_DPS_PER_LSB, TEMP_C_PER_LSB
from station.domain.signals.samples import SAMPLE_COLUMNS, SampleBlock

PROTOCOL_VERSION: Final = 1
SYNC: Final = b"\xa5\x5a"
HEADER_BYTES: Final = 4  # sync, type, length
CRC_BYTES: Final = 2
FRAME_OVERHEAD: Final = HEADER_BYTES + CRC_BYTES
CRC_INIT: Final = 0xFFFF

#: Largest rate of the calibrated stream: its 28-byte frames fill 230,400 baud at 822/s.
MAX_CALIBRATED_RATE_HZ: Final = 800
#: Baud rate of the link (8N1: 10 bits on the wire per byte).
DEFAULT_BAUD: Final = 230_400
TEXT_FIELD_BYTES: Final = {"serial": 16, "firmware": 8, "sensor_part": 16}
MAX_ERROR_TEXT: Final = 64


class FrameType(IntEnum):
    """Frame types. Host to putter: 0x10…0x1F; putter to host: 0x01, 0x02, 0x80…0x8F."""

    SAMPLE = 0x01
    CAL_SAMPLE = 0x02
    IDENTIFY = 0x10
    START_STREAM = 0x11
    STOP_STREAM = 0x12
    SET_RATE = 0x13
    WRITE_CAL = 0x14
    READ_CAL = 0x15
    WRITE_GYRO_CAL = 0x16
    READ_GYRO_CAL = 0x17
    ACK = 0x80
    IDENTITY = 0x81
    CALIBRATION = 0x82
    GYRO_CALIBRATION = 0x83
    ERROR = 0x8F


class ErrorCode(IntEnum):
    """Codes of the error reply."""

    UNKNOWN_COMMAND = 1
    BAD_LENGTH = 2
    BAD_VALUE = 3


class StreamMode(IntEnum):
    """What START_STREAM asks for."""

    RAW = 0
    CALIBRATED = 1


SAMPLE_STRUCT: Final = struct.Struct("<H3H3hh")
CAL_SAMPLE_STRUCT: Final = struct.Struct("<H3f3hh")
IDENTITY_STRUCT: Final = struct.Struct("<B16s8s16s")
CALIBRATION_STRUCT: Final = struct.Struct("<12f")
CALIBRATION_REPLY_STRUCT: Final = struct.Struct("<B12f")
RATE_STRUCT: Final = struct.Struct("<H")

#: numpy views of the two sample payloads, for decoding many at once.
SAMPLE_DTYPE: Final = np.dtype(
    [("seq", "<u2"), ("acc", "<u2", (3,)), ("gyro", "<i2", (3,)), ("temp", "<i2")]
)
CAL_SAMPLE_DTYPE: Final = np.dtype(
    [("seq", "<u2"), ("acc", "<f4", (3,)), ("gyro", "<i2", (3,)), ("temp", "<i2")]
)

#: Allowed payload length (minimum, maximum) of every frame type.
PAYLOAD_LENGTHS: Final[dict[int, tuple[int, int]]] = {
    FrameType.SAMPLE: (SAMPLE_STRUCT.size, SAMPLE_STRUCT.size),
    FrameType.CAL_SAMPLE: (CAL_SAMPLE_STRUCT.size, CAL_SAMPLE_STRUCT.size),
    FrameType.IDENTIFY: (0, 0),
    FrameType.START_STREAM: (1, 1),
    FrameType.STOP_STREAM: (0, 0),
    FrameType.SET_RATE: (RATE_STRUCT.size, RATE_STRUCT.size),
    FrameType.WRITE_CAL: (CALIBRATION_STRUCT.size, CALIBRATION_STRUCT.size),
    FrameType.READ_CAL: (0, 0),
    FrameType.WRITE_GYRO_CAL: (CALIBRATION_STRUCT.size, CALIBRATION_STRUCT.size),
    FrameType.READ_GYRO_CAL: (0, 0),
    FrameType.ACK: (1, 1),
    FrameType.IDENTITY: (IDENTITY_STRUCT.size, IDENTITY_STRUCT.size),
    FrameType.CALIBRATION: (CALIBRATION_REPLY_STRUCT.size, CALIBRATION_REPLY_STRUCT.size),
    FrameType.GYRO_CALIBRATION: (CALIBRATION_REPLY_STRUCT.size, CALIBRATION_REPLY_STRUCT.size),
    FrameType.ERROR: (2, 2 + MAX_ERROR_TEXT),
}


@dataclass(frozen=True, slots=True)
class Frame:
    """One frame whose header and CRC checked out."""

    type: int
    payload: bytes


def encode_frame(frame_type: int, payload: bytes = b"") -> bytes:
    """Frame ``payload`` as ``frame_type``: sync, header, payload, CRC."""
    if len(payload) > 0xFF:
        raise ValueError(f"payload of {len(payload)} bytes does not fit a frame (max 255)")
    body = bytes((frame_type, len(payload))) + payload
    return SYNC + body + crc_hqx(body, CRC_INIT).to_bytes(2, "big")


class FrameParser:
    """Incremental frame reader that resynchronises after garbage.

    Feed it bytes as they come; it returns the frames completed so far and keeps the
    unfinished tail. A frame is accepted only when its type is known, its length is
    the one that type allows and its CRC matches; otherwise the parser slides one
    byte past the sync word it tried and hunts for the next one. With ``lengths=None``
    (the putter's side) any type and length pass to the CRC check, so that a well-framed
    but unknown or malformed command can be answered with an error reply. Counters:

    - ``frames``: frames accepted;
    - ``crc_errors``: well-formed headers whose CRC did not match;
    - ``bad_headers``: sync words followed by an unknown type or impossible length;
    - ``resyncs``: times the parser lost alignment and skipped bytes to find a frame;
    - ``bytes_discarded``: bytes skipped while hunting.
    """

    def __init__(self, lengths: Mapping[int, tuple[int, int]] | None = PAYLOAD_LENGTHS) -> None:
        self._lengths = lengths
        self._buf = bytearray()
        self._hunting = False
        self.frames = 0
        self.crc_errors = 0
        self.bad_headers = 0
        self.resyncs = 0
        self.bytes_discarded = 0

    def _skip(self, count: int) -> None:
        self.bytes_discarded += count
        if not self._hunting:
            self._hunting = True
            self.resyncs += 1

    def feed(self, data: bytes | bytearray | memoryview) -> list[Frame]:
        """Add ``data`` to the stream; return the frames it completed, in order."""
        buf = self._buf
        buf += data
        found: list[Frame] = []
        pos = 0
        size = len(buf)
        lengths = self._lengths
        while True:
            start = buf.find(SYNC, pos)
            if start < 0:
                # Keep a trailing first sync byte: its partner may come in the next read.
                keep = size - 1 if size > pos and buf[-1] == SYNC[0] else size
                if keep > pos:
                    self._skip(keep - pos)
                pos = keep
                break
            if start > pos:
                self._skip(start - pos)
                pos = start
            if size - pos < HEADER_BYTES:
                break
            frame_type = buf[pos + 2]
            length = buf[pos + 3]
            bounds = (0, 0xFF) if lengths is None else lengths.get(frame_type)
            if bounds is None or not bounds[0] <= length <= bounds[1]:
                self.bad_headers += 1
                self._skip(1)
                pos += 1
                continue
            end = pos + HEADER_BYTES + length + CRC_BYTES
            if end > size:
                break
            crc = (buf[end - 2] << 8) | buf[end - 1]
            if crc_hqx(buf[pos + 2 : end - 2], CRC_INIT) != crc:
                self.crc_errors += 1
                self._skip(1)
                pos += 1
                continue
            found.append(Frame(frame_type, bytes(buf[pos + HEADER_BYTES : end - 2])))
            self._hunting = False
            pos = end
        del buf[:pos]
        self.frames += len(found)
        return found


def encode_sample(
    seq: int, acc: tuple[int, int, int], gyro: tuple[int, int, int], temp: int
) -> bytes:
    """One raw SAMPLE frame; ``gyro`` and ``temp`` in protocol counts."""
    return encode_frame(FrameType.SAMPLE, SAMPLE_STRUCT.pack(seq & 0xFFFF, *acc, *gyro, temp))


def decode_samples(payloads: list[bytes], calibrated: bool = False) -> SampleBlock:
    """Decode SAMPLE (or CAL_SAMPLE) payloads into a block of samples.

    The sequence numbers are the 16-bit ones as sent; accelerometer in ADC counts (g
    for calibrated samples), gyros in deg/s, temperature in °C.
    """
    dtype = CAL_SAMPLE_DTYPE if calibrated else SAMPLE_DTYPE
    rec = np.frombuffer(b"".join(payloads), dtype=dtype)
    block = SampleBlock(np.empty((rec.shape[0], len(SAMPLE_COLUMNS)), dtype=np.float64))
    block.seq[:] = rec["seq"]
    block.accel[:] = rec["acc"]
    block.gyro[:] = rec["gyro"] * GYRO_DPS_PER_LSB
    block.temperature[:] = rec["temp"] * TEMP_C_PER_LSB
    return block


def encode_text(value: str, width: int) -> bytes:
    """ASCII text field of ``width`` bytes, NUL padded."""
    raw = value.encode("ascii")
    if len(raw) > width:
        raise ValueError(f"{value!r} is longer than the {width}-byte field")
    return raw.ljust(width, b"\0")


def decode_text(raw: bytes) -> str:
    """Inverse of :func:`encode_text`; undecodable bytes become U+FFFD."""
    return raw.rstrip(b"\0").decode("ascii", errors="replace")
