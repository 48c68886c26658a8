"""The spread screen: a window it refuses the judge refuses for its spread, and a window
clearly spread too far it refuses (the live detector's cheap screen)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from station.domain.sensors.sensor_spec import PUTTER_SENSOR
from station.domain.signals.samples import SampleBlock
from station.domain.signals.stillness import SpreadScreen, StillnessThresholds, judge_window

LIMITS = StillnessThresholds()
ADC_MAX = PUTTER_SENSOR.adc_max


def block_of(counts: np.ndarray) -> SampleBlock:
    n = len(counts)
    return SampleBlock.from_columns(
        np.arange(n, dtype=np.float64),
        counts.astype(np.float64),
        np.zeros((n, 3)),
        np.full(n, 25.0),
    )


@st.composite
def windows(draw: st.DrawFn) -> tuple[np.ndarray, int, int]:
    """Counts near a still pose, some axes noisier than the limit, some touching a rail."""
    n = draw(st.integers(2, 300))
    centre = np.array([2048, 2048, 2867])
    spread = draw(hnp.arrays(np.int64, 3, elements=st.integers(0, 12)))
    noise = draw(hnp.arrays(np.int64, (n, 3), elements=st.integers(-1, 1)))
    counts = centre + noise * spread
    if draw(st.booleans()):
        axis, row = draw(st.integers(0, 2)), draw(st.integers(0, n - 1))
        counts[row, axis] = draw(st.sampled_from([0, ADC_MAX]))
    start = draw(st.integers(0, n - 2))
    stop = draw(st.integers(start + 2, n))
    return counts, start, stop


@given(windows())
@settings(max_examples=300)
def test_a_window_the_screen_refuses_the_judge_refuses_for_its_spread(
    case: tuple[np.ndarray, int, int],
) -> None:
    counts, start, stop = case
    screen = SpreadScreen(counts.astype(np.float64), LIMITS.accel_std_max_counts, ADC_MAX)
    verdict = judge_window(block_of(counts[start:stop]), LIMITS)
    exact = counts[start:stop].std(axis=0, ddof=1)
    free = ~np.any((counts[start:stop] <= 0) | (counts[start:stop] >= ADC_MAX), axis=0)
    if screen.refuses(start, stop):
        assert verdict.motion
        assert any("spread" in reason for reason in verdict.reasons)
    if np.any(exact[free] > LIMITS.accel_std_max_counts * 1.001):
        assert screen.refuses(start, stop)


def test_a_stream_not_in_whole_counts_screens_nothing() -> None:
    accel = np.array([[0.0, 0.0, 1.0], [0.5, 0.0, 1.0], [-0.5, 0.0, 1.0]]) * 100.5
    screen = SpreadScreen(accel, 1e-6, ADC_MAX)
    assert not screen.refuses(0, 3)
