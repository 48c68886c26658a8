"""Framing, CRC and codecs of the serial protocol, fuzzed."""

from binascii import crc_hqx

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.device.messages import DeviceCalibration, Identity
from station.device.protocol import (
    FRAME_OVERHEAD,
    SAMPLE_STRUCT,
    SYNC,
    Frame,
    FrameParser,
    FrameType,
    decode_samples,
    encode_frame,
    encode_sample,
)
from tests.conftest import examples

samples = st.tuples(
    st.integers(0, 0xFFFF),
    st.tuples(*[st.integers(0, 4095)] * 3),
    st.tuples(*[st.integers(-32768, 32767)] * 3),
    st.integers(-32768, 32767),
)


def sample_frame(sample: tuple[int, tuple[int, int, int], tuple[int, int, int], int]) -> bytes:
    seq, acc, gyro, temp = sample
    return encode_sample(seq, acc, gyro, temp)


def test_frame_layout_is_sync_header_payload_crc() -> None:
    frame = encode_frame(FrameType.SET_RATE, b"\xf4\x01")
    assert frame[:2] == SYNC
    assert frame[2:4] == bytes((FrameType.SET_RATE, 2))
    assert frame[4:6] == b"\xf4\x01"
    # CRC-16/CCITT-FALSE check value of the standard "123456789" is 0x29B1.
    assert crc_hqx(b"123456789", 0xFFFF) == 0x29B1
    assert int.from_bytes(frame[6:], "big") == crc_hqx(frame[2:6], 0xFFFF)
    assert len(frame) == 2 + FRAME_OVERHEAD


def test_sample_frame_is_22_bytes_and_decodes_to_physical_units() -> None:
    frame = encode_sample(65535, (0, 2048, 4095), (-50, 0, 50), 2512)
    assert len(frame) == 22
    (parsed,) = FrameParser().feed(frame)
    row = decode_samples([parsed.payload]).rows[0]
    np.testing.assert_allclose(row, [65535, 0, 2048, 4095, -1.0, 0.0, 1.0, 25.12])


def test_frames_split_across_reads_come_out_whole() -> None:
    stream = b"".join(encode_sample(i, (1, 2, 3), (4, 5, 6), 7) for i in range(50))
    parser = FrameParser()
    frames: list[Frame] = []
    for i in range(0, len(stream), 7):
        frames += parser.feed(stream[i : i + 7])
    assert [SAMPLE_STRUCT.unpack(f.payload)[0] for f in frames] == list(range(50))
    assert parser.resyncs == parser.crc_errors == parser.bytes_discarded == 0


def test_garbage_before_a_frame_counts_one_resync() -> None:
    parser = FrameParser()
    frames = parser.feed(b"\x00\xa5\x13\x5a\xff" + encode_frame(FrameType.ACK, b"\x10"))
    assert frames == [Frame(FrameType.ACK, b"\x10")]
    assert parser.resyncs == 1
    assert parser.bytes_discarded == 5


def test_a_corrupted_frame_is_refused_and_the_next_one_read() -> None:
    good = encode_sample(1, (1, 2, 3), (0, 0, 0), 0)
    bad = bytearray(good)
    bad[8] ^= 0x04
    parser = FrameParser()
    frames = parser.feed(bytes(bad) + good)
    assert len(frames) == 1
    assert frames[0].payload == good[4:-2]
    assert parser.crc_errors == 1
    assert parser.resyncs == 1


def test_unknown_type_or_wrong_length_is_refused_before_the_crc() -> None:
    parser = FrameParser()
    assert parser.feed(encode_frame(0x33, b"")) == []
    assert parser.feed(encode_frame(FrameType.SAMPLE, b"\x00" * 15)) == []
    assert parser.bad_headers == 2
    assert parser.crc_errors == 0


def test_the_putter_side_parser_passes_any_well_framed_command() -> None:
    frames = FrameParser(lengths=None).feed(encode_frame(0x33, b"abc"))
    assert frames == [Frame(0x33, b"abc")]


def test_payload_too_long_for_a_frame_is_refused() -> None:
    with pytest.raises(ValueError, match="max 255"):
        encode_frame(FrameType.ERROR, b"x" * 256)


@given(
    st.text(st.characters(min_codepoint=33, max_codepoint=126), max_size=16),
    st.text(st.characters(min_codepoint=33, max_codepoint=126), max_size=8),
)
def test_identity_round_trips(serial: str, firmware: str) -> None:
    identity = Identity(serial, firmware, "KXM52-1050")
    assert Identity.decode(identity.encode()) == identity


@given(
    st.lists(st.floats(1500, 2600), min_size=3, max_size=3),
    st.lists(st.floats(-0.002, 0.002), min_size=9, max_size=9),
)
def test_calibration_round_trips_exactly_at_float32(
    offset: list[float], matrix: list[float]
) -> None:
    sent = DeviceCalibration(np.array(offset), np.array(matrix).reshape(3, 3))
    back = DeviceCalibration.decode(sent.encode())
    np.testing.assert_array_equal(back.offset, sent.offset)
    np.testing.assert_array_equal(back.matrix, sent.matrix)
    # float32 keeps offsets to 2^-24 relative: well below a thousandth of a count.
    np.testing.assert_allclose(sent.offset, offset, rtol=2**-24)


def test_calibration_refuses_wrong_shapes_and_non_finite_values() -> None:
    with pytest.raises(ValueError, match="3 offsets"):
        DeviceCalibration(np.zeros(2), np.eye(3))
    with pytest.raises(ValueError, match="finite"):
        DeviceCalibration(np.array([0.0, np.nan, 0.0]), np.eye(3))


# -- fuzzing: never a crash, never a sample that was not sent -----------------------


def accepted_subsequence(accepted: list[bytes], sent: list[bytes]) -> bool:
    remaining = iter(sent)
    return all(any(a == s for s in remaining) for a in accepted)


@settings(max_examples=examples(300))
@given(
    st.lists(st.tuples(samples, st.binary(max_size=40)), max_size=30),
    st.lists(st.integers(1, 64), min_size=1, max_size=10),
)
def test_garbage_between_frames_never_costs_a_good_frame(
    items: list[tuple[tuple[int, tuple[int, int, int], tuple[int, int, int], int], bytes]],
    splits: list[int],
) -> None:
    sent = [sample_frame(s) for s, _ in items]
    # Garbage free of the sync word cannot look like the start of a frame.
    garbage = [g.replace(SYNC[:1], b"\x00") for _, g in items]
    stream = b"".join(g + f for f, g in zip(sent, garbage, strict=True))
    parser = FrameParser()
    accepted: list[bytes] = []
    pos = 0
    for cut in splits * (len(stream) // max(1, sum(splits)) + 1):
        accepted += [f.payload for f in parser.feed(stream[pos : pos + cut])]
        pos += cut
    assert accepted == [f[4:-2] for f in sent]


@settings(max_examples=examples(300))
@given(
    st.lists(samples, min_size=1, max_size=20),
    st.lists(st.tuples(st.integers(0, 10_000), st.integers(0, 7)), max_size=3),
    st.integers(0, 21),
    st.binary(max_size=64),
)
def test_bit_flips_truncation_and_garbage_never_yield_a_wrong_sample(
    items: list[tuple[int, tuple[int, int, int], tuple[int, int, int], int]],
    flips: list[tuple[int, int]],
    truncate: int,
    garbage: bytes,
) -> None:
    sent = [sample_frame(s) for s in items]
    stream = bytearray(garbage + b"".join(sent))
    for position, bit in flips:
        stream[position % len(stream)] ^= 1 << bit
    del stream[len(stream) - truncate :]
    parser = FrameParser()
    accepted = [f.payload for f in parser.feed(bytes(stream))]
    payloads = [f[4:-2] for f in sent]
    assert accepted_subsequence(accepted, payloads)
    assert len(accepted) >= len(sent) - len(flips) - 2 - (len(garbage) > 0)
    assert parser.frames == len(accepted)


@settings(max_examples=examples(200))
@given(st.binary(max_size=2000))
def test_random_bytes_never_crash_the_parser(noise: bytes) -> None:
    parser = FrameParser()
    frames = parser.feed(noise)
    consumed = sum(len(f.payload) + FRAME_OVERHEAD for f in frames)
    assert consumed + parser.bytes_discarded <= len(noise)
    # Whatever is still held is at most one frame in the making.
    assert len(noise) - consumed - parser.bytes_discarded <= 255 + FRAME_OVERHEAD
