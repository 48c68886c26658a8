"""Declared units of a recorded stream: converted exactly, contradicted ones named."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.domain.gyro.motion import StreamError
from station.domain.gyro.motion.stream import RecordedStream
from station.domain.gyro.motion.stream_units import StreamUnits, check_units, convert

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
