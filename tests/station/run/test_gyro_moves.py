"""The gyro stream between captures: moves cut at the still windows, restarts named."""

import itertools

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.device import LinkCounters
from station.domain.calibration import Calibration
from station.domain.gyro.motion import GyroMatrixError, Move
from station.domain.product.run_settings import RunSettings
from station.domain.signals.samples import SampleBlock
from station.run.acquisition import PoseResult
from station.run.gyro import LiveGyro
from station.run.gyro_moves import MoveRecorder
from station.run.verdict import MESSAGE_MAX, gyro_matrix_failed

RATE = 500.0


def block(first: int, last: int, rate_dps: float = 0.0) -> SampleBlock:
    seq = np.arange(first, last + 1, dtype=np.float64)
    n = len(seq)
    return SampleBlock.from_columns(
        seq, np.full((n, 3), 2048.0), np.full((n, 3), rate_dps), np.full(n, 25.0)
    )


def still(first: int, last: int) -> PoseResult:
    window = block(first, last)
    return PoseResult(
        pose=None,
        summary=window.summary(),
        first_seq=first,
        last_seq=last,
        duration_s=window.span / RATE,
        wait_s=0.0,
        loss_fraction=0.0,
        link=LinkCounters(),
    )


@given(cuts=st.lists(st.integers(1, 400), min_size=1, max_size=8))
def test_a_move_runs_from_the_end_of_one_window_to_the_start_of_the_next(
    cuts: list[int],
) -> None:
    recorder = MoveRecorder(RATE)
    edges = 100 + np.cumsum([0, *cuts, 900])
    recorder.feed(block(0, 99))
    recorder.captured(0, still(0, 99))
    for a, b in itertools.pairwise(edges):
        piece = block(int(a), int(b) - 1, 10.0)
        recorder.feed(piece)
        recorder.feed(piece)  # a block handed twice (a failed poll) counts once
    end = int(edges[-1]) - 1
    recorder.captured(1, still(end - 99, end))
    (move,) = recorder.moves
    assert (move.before, move.after, move.unusable) == (0, 1, None)
    np.testing.assert_array_equal(move.seq, np.arange(99, end - 98))
    t = recorder.times(move)
    assert Move(t, move.gyro_dps, np.eye(3)[2], np.eye(3)[2]).problem() is None


def test_a_restarted_stream_makes_the_move_unusable_and_says_why() -> None:
    recorder = MoveRecorder(RATE)
    recorder.feed(block(0, 1999))
    recorder.captured(0, still(1000, 1999))
    recorder.feed(block(0, 1499))  # the unit was reconnected: its numbers start again
    recorder.captured(1, still(500, 1499))
    (move,) = recorder.moves
    assert move.unusable == "the stream restarted during the move (the unit was reconnected)"
    assert len(move.seq) == 0


def test_lost_samples_inside_a_move_are_a_gap_the_fit_names() -> None:
    recorder = MoveRecorder(RATE)
    recorder.feed(block(0, 999))
    recorder.captured(0, still(0, 999))
    recorder.feed(block(1000, 1400))
    recorder.feed(block(1403, 2999))  # two samples lost on the link
    recorder.captured(1, still(2000, 2999))
    (move,) = recorder.moves
    assert move.unusable is None
    problem = Move(recorder.times(move), move.gyro_dps, np.eye(3)[0], np.eye(3)[0]).problem()
    assert problem is not None
    assert problem.startswith("gap of 0.006 s")


def test_moves_a_lossy_link_cut_up_fail_the_fit_in_one_bounded_reason() -> None:
    recorder = MoveRecorder(RATE)
    gyro = LiveGyro(RATE, RunSettings())
    for pose in range(13):
        start = pose * 3000
        recorder.feed(block(start, start + 1000))
        recorder.feed(block(start + 1003, start + 2999))  # samples lost on the link
        recorder.captured(pose, still(start + 2000, start + 2999))
    gyro.recorder = recorder
    calibration = Calibration.from_sensitivity([2048.0, 2048.0, 1228.8], [819.2] * 3)
    with pytest.raises(GyroMatrixError, match="needs 6 usable moves, got 0 of 12") as info:
        gyro.fit_matrix(calibration, np.zeros(3))
    reason = gyro_matrix_failed(info.value)
    assert reason.code == "gyro_matrix"
    assert len(reason.message) <= MESSAGE_MAX
    assert reason.message.startswith("gyro matrix: gyro matrix needs 6 usable moves")
