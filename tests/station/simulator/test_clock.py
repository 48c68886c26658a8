"""The virtual clock runs faster than real time."""

import time

import pytest

from station.simulator import VirtualClock


def test_simulated_time_runs_speed_times_faster() -> None:
    clock = VirtualClock(speed=50.0)
    started = time.monotonic()
    clock.sleep(5.0)
    real = time.monotonic() - started
    assert 0.09 <= real < 0.5
    assert clock.now() == pytest.approx(real * 50.0, rel=0.2)


def test_speed_must_be_positive() -> None:
    with pytest.raises(ValueError, match="positive"):
        VirtualClock(speed=0.0)
