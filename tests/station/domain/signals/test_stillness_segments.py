"""The live stillness judge segments a recorded stream into its still poses."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from station.domain.signals.samples import SampleBlock
from station.domain.signals.stillness import StillnessThresholds, judge_window, still_segments

LIMITS = StillnessThresholds(window_samples=100, hop_samples=10)


def _stream(layout: list[tuple[bool, int]], seed: int) -> tuple[SampleBlock, list[range]]:
    """Alternating still stretches (±1 g on z, then x) and turning stretches."""
    rng = np.random.default_rng(seed)
    accel, gyro, stills, at = [], [], [], 0
    for k, (still, n) in enumerate(layout):
        if still:
            g = np.array([0.0, 0.0, 819.2]) if k % 4 == 0 else np.array([819.2, 0.0, 0.0])
            accel.append(2048 + g + rng.normal(0, 1.0, (n, 3)))
            gyro.append(rng.normal(0, 0.05, (n, 3)))
            stills.append(range(at, at + n))
        else:
            angle = np.linspace(0, np.pi / 2, n)
            accel.append(2048 + 819.2 * np.column_stack([np.sin(angle), 0 * angle, np.cos(angle)]))
            gyro.append(np.tile([0.0, 90.0, 0.0], (n, 1)))
        at += n
    a, w = np.concatenate(accel), np.concatenate(gyro)
    return SampleBlock.from_columns(np.arange(len(a), dtype=float), a, w, np.zeros(len(a))), stills


@settings(max_examples=25, deadline=None)
@given(
    lengths=st.lists(st.integers(150, 600), min_size=2, max_size=6),
    moves=st.lists(st.integers(40, 300), min_size=5, max_size=5),
    seed=st.integers(0, 2**32 - 1),
)
def test_each_still_stretch_is_one_segment_inside_it(
    lengths: list[int], moves: list[int], seed: int
) -> None:
    layout: list[tuple[bool, int]] = []
    for i, n in enumerate(lengths):
        if i:
            layout.append((False, moves[i - 1]))
        layout.append((True, n))
    block, stills = _stream(layout, seed)
    segments = still_segments(block, LIMITS)
    assert len(segments) == len(stills)
    for segment, still in zip(segments, stills, strict=True):
        assert still.start <= segment.start < segment.stop <= still.stop
        # Windows start every hop: at most a hop of the stretch is lost at each end.
        assert segment.start - still.start < LIMITS.hop_samples
        assert still.stop - segment.stop < LIMITS.hop_samples + LIMITS.window_samples // 2
        assert judge_window(block[segment.start : segment.stop], LIMITS).still


def test_a_sequence_gap_breaks_stillness_as_live() -> None:
    block, _ = _stream([(True, 400)], 1)
    gapped = SampleBlock(block.rows.copy())
    gapped.seq[200:] += 50  # 50 samples lost on the link in the middle
    segments = still_segments(gapped, LIMITS)
    assert all(s.stop <= 200 or s.start >= 200 for s in segments)
    assert len(segments) == 2
