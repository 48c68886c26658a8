"""Declared units of a recorded stream: converted exactly, contradicted ones named."""

import re

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from station.domain.gyro.motion import Move, StreamError
from station.domain.gyro.motion.stream import RecordedStream
from station.domain.gyro.motion.stream_units import (
    StreamUnits,
    check_declared,
    check_turns,
    check_units,
    convert,
)

rows = st.integers(2, 50)
seeds = st.integers(0, 2**32 - 1)


def _stream(n: int, seed: int) -> RecordedStream:
    rng = np.random.default_rng(seed)
    return RecordedStream(
        t=np.cumsum(rng.uniform(0.001, 0.01, n)),
        accel_counts=rng.uniform(0, 4095, (n, 3)),
        gyro_dps=rng.uniform(-500, 500, (n, 3)),
    )


@given(n=rows, seed=seeds)
def test_every_declared_unit_converts_back_to_the_station_s(n: int, seed: int) -> None:
    own = _stream(n, seed)
    g = (own.accel_counts - 2048.0) / 819.2
    foreign = RecordedStream(
        t=own.t * 1000.0, accel_counts=g * 9.80665, gyro_dps=np.radians(own.gyro_dps)
    )
    back = convert(foreign, StreamUnits(accel="m/s2", gyro="rads", time="ms"))
    np.testing.assert_allclose(back.accel_counts, own.accel_counts, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(back.gyro_dps, own.gyro_dps, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(back.t, own.t, rtol=1e-12)
    in_g = convert(
        RecordedStream(t=own.t, accel_counts=g, gyro_dps=own.gyro_dps), StreamUnits(accel="g")
    )
    np.testing.assert_allclose(in_g.accel_counts, own.accel_counts, rtol=1e-12, atol=1e-9)
    assert convert(own, StreamUnits()) == own or np.array_equal(
        convert(own, StreamUnits()).t, own.t
    )


@given(n=rows, seed=seeds, rate=st.floats(1.0, 5000.0))
def test_a_declared_rate_replaces_the_time_column(n: int, seed: int, rate: float) -> None:
    stream = convert(_stream(n, seed), StreamUnits(rate_hz=rate))
    np.testing.assert_allclose(stream.t, np.arange(n) / rate)
    assert stream.rate_hz == pytest.approx(rate)


@given(reads=st.sampled_from([(1.0, "g"), (9.80665, "m/s2")]), seed=seeds)
def test_an_accelerometer_reading_1_or_9_8_at_rest_is_not_counts(
    reads: tuple[float, str], seed: int
) -> None:
    magnitude, option = reads
    rng = np.random.default_rng(seed)
    direction = rng.standard_normal(3)
    accel = np.tile(direction / np.linalg.norm(direction) * magnitude, (100, 1))
    stream = RecordedStream(
        t=np.arange(100) / 100.0, accel_counts=accel, gyro_dps=np.zeros((100, 3))
    )
    with pytest.raises(StreamError, match=f"at rest: .*use --accel-units {option}$"):
        check_units(stream, StreamUnits())
    check_units(convert(stream, StreamUnits(accel=option)), StreamUnits(accel=option))


def test_a_rate_that_is_not_one_is_refused() -> None:
    for rate in (0.0, -1.0, float("inf")):
        with pytest.raises(StreamError, match="not a positive rate"):
            StreamUnits(rate_hz=rate)


@given(
    n=st.integers(20, 200),
    rate=st.floats(20.0, 2000.0),
    factor=st.one_of(st.floats(0.05, 0.85), st.floats(1.15, 20.0)),
)
def test_a_declared_rate_the_time_column_contradicts_is_refused(
    n: int, rate: float, factor: float
) -> None:
    raw = RecordedStream(
        t=np.arange(n) / rate,
        accel_counts=np.tile([2048.0, 2048.0, 2867.2], (n, 1)),
        gyro_dps=np.zeros((n, 3)),
    )
    with pytest.raises(StreamError, match=r"^stream: --rate .* leave out --rate$"):
        check_declared(raw, StreamUnits(rate_hz=rate * factor))
    check_declared(raw, StreamUnits(rate_hz=rate * 1.05))
    # A time column that is no time in seconds (sample numbers) cannot contradict a rate.
    numbered = RecordedStream(
        t=np.arange(n) + 1.0, accel_counts=raw.accel_counts, gyro_dps=raw.gyro_dps
    )
    check_declared(numbered, StreamUnits(rate_hz=rate * factor))


def _move(angle_deg: float, axis_seed: int, scale: float) -> Move:
    """A move turning at a constant rate by ``angle_deg`` about an axis square to gravity,
    its rates read ``scale`` times too large (a wrong unit): gravity turns by the angle."""
    rng = np.random.default_rng(axis_seed)
    before = rng.standard_normal(3)
    before /= np.linalg.norm(before)
    axis = np.cross(before, rng.standard_normal(3))
    axis /= np.linalg.norm(axis)
    t = np.linspace(0.0, 1.0, 201)
    turn = Rotation.from_rotvec(np.radians(angle_deg) * axis)
    return Move(
        t=t,
        rates_dps=np.tile(angle_deg * axis * scale, (len(t), 1)),
        gravity_before=before,
        gravity_after=turn.inv().apply(before),
    )


@given(
    angles=st.lists(st.floats(30.0, 175.0), min_size=1, max_size=8),
    seed=seeds,
    scale=st.one_of(st.floats(0.01, 0.45), st.floats(11.0, 100.0), st.floats(0.6, 9.0)),
    gyro=st.sampled_from(["dps", "rads"]),
)
def test_gyro_units_the_moves_contradict_are_refused(
    angles: list[float], seed: int, scale: float, gyro: str
) -> None:
    # A move about an axis square to gravity turns gravity by its whole angle, so the
    # swept angle over gravity's is the factor the rates are read wrong by.
    moves = [_move(a, seed + i, scale) for i, a in enumerate(angles)]
    units = StreamUnits(gyro="rads" if gyro == "rads" else "dps")
    if 0.5 <= scale <= 10.0:
        check_turns(moves, np.zeros(3), units)
        return
    with pytest.raises(StreamError) as refused:
        check_turns(moves, np.zeros(3), units)
    message = str(refused.value)
    found = re.match(r"stream: the gyros turn (\S+) times as far as gravity turns", message)
    assert found is not None, message
    assert float(found.group(1)) == pytest.approx(scale, rel=0.01)
    if gyro == "rads" and scale > 10:
        assert message.endswith("--gyro-units rads, but deg/s? use --gyro-units dps")
    if gyro == "dps" and scale < 0.5:
        assert message.endswith("rad/s? use --gyro-units rads")
