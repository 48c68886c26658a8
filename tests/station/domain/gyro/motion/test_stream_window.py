"""The still window fitted to a recording's rests
(:func:`station.domain.gyro.motion.stream.chosen_window`)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from station.domain.constants import STILL_WINDOW_S
from station.domain.gyro.motion import calibrate_stream
from station.domain.gyro.motion.stream import MIN_WINDOW_S, chosen_window
from station.simulator.recording import (
    StreamPlan,
    pose_orientations,
    random_imu,
    recorded_stream,
    spread_directions,
)


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), still_s=st.floats(0.8, 4.0))
def test_every_rest_of_a_recording_is_found_whatever_its_length(seed: int, still_s: float) -> None:
    # Twelve rests of still_s seconds: the window fits them (about half a rest, between
    # 0.5 and 1 s) and each rest is one pose, none split, none lost.
    rng = np.random.default_rng(seed)
    plan = StreamPlan(rate_hz=200.0, still_s=still_s, move_s=1.0)
    stream = recorded_stream(
        rng, random_imu(rng), pose_orientations(rng, spread_directions(12)), plan
    )
    window = chosen_window(stream, "nine").window_samples / stream.rate_hz
    assert MIN_WINDOW_S - 1e-9 <= window <= STILL_WINDOW_S + 1e-9
    if still_s >= 2 * STILL_WINDOW_S + 0.1:
        # Rests of two default windows or more are judged on the default window.
        assert window == round(STILL_WINDOW_S * stream.rate_hz) / stream.rate_hz
    result = calibrate_stream(stream, "nine")
    assert len(result.stills) == 12
    assert result.still_window_s == window
