"""The virtual clock runs faster than real time."""

import time

import pytest

from station.simulator import VirtualClock


def test_simulated_time_runs_speed_times_faster() -> None:
    before = time.monotonic()
    clock = VirtualClock(speed=50.0)
    after = time.monotonic()
    clock.sleep(5.0)
    # Slept at least 5 simulated seconds, i.e. 0.1 s of real time (more when the
    # machine is busy: only the lower bound holds whatever the load).
    assert time.monotonic() - after >= 0.1
    start = time.monotonic()
    now = clock.now()
    end = time.monotonic()
    # The simulated time is 50 × the real time since the clock was made, bracketed by
    # the readings of the real clock around its creation and around the reading.
    assert (start - after) * 50.0 <= now <= (end - before) * 50.0
    assert now >= 5.0


def test_speed_must_be_positive() -> None:
    with pytest.raises(ValueError, match="positive"):
        VirtualClock(speed=0.0)
