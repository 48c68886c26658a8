"""The gyro stream between the captures of a run: the moves the gyro matrix is fitted to.

A whole-unit run keeps every raw sample the station drains while it takes its poses
(:class:`MoveRecorder`). When a pose is captured, the samples from the last sample of
the previous still window to the first sample of this one, both included, are one move
([Tedaldi2014]_): its sequence numbers (the time base: a lost sample is a gap the fit
names), its gyro rates and the raw accelerometer readings, and the two poses' mean
counts, which the solved calibration turns into gravity directions at the end.

The unit restarts its sequence numbers with every stream (a reconnection): a move over
such a restart cannot be integrated and is kept as unusable, with the reason. Only the
samples since the last capture are held, at most :data:`MAX_MOVE_S` of them.
"""

from dataclasses import dataclass
from typing import Final

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.signals.samples import SampleBlock
from station.run.acquisition import PoseResult

#: Longest move kept, in device seconds (a unit left lying is no move).
MAX_MOVE_S: Final = 120.0


@dataclass(frozen=True)
class _Still:
    """A captured window: pose index, stream epoch, its first and last sample, mean counts."""

    index: int
    epoch: int
    first_seq: int
    last_seq: int
    accel_mean: FloatArray


@dataclass(frozen=True, eq=False)
class RecordedMove:
    """The samples between two captured poses (``before``, ``after``: pose indexes).

    ``seq`` are the unwrapped sequence numbers, ``gyro_dps`` (n, 3) the raw rates,
    ``accel_counts`` (n, 3) the raw accelerometer; ``mean_before``/``mean_after`` the
    two poses' mean counts. ``unusable`` says why the move has no samples to integrate.
    """

    before: int
    after: int
    seq: FloatArray
    gyro_dps: FloatArray
    accel_counts: FloatArray
    mean_before: FloatArray
    mean_after: FloatArray
    unusable: str | None = None


class MoveRecorder:
    """The raw samples since the last capture, and the moves recorded so far."""

    def __init__(self, rate_hz: float) -> None:
        self._rate_hz = rate_hz
        self._pending: list[SampleBlock] = []
        self._pending_rows = 0
        self._truncated = False
        self._epoch = 0
        self._last_seq = -1.0
        self._last_block: SampleBlock | None = None
        self._still: _Still | None = None
        self.moves: list[RecordedMove] = []

    def feed(self, block: SampleBlock) -> None:
        """Take in the samples the station drained (a block handed twice counts once)."""
        if block is self._last_block or not len(block):
            return
        self._last_block = block
        if block.seq[0] <= self._last_seq:  # the unit started a new stream
            self._epoch += 1
            self._pending, self._pending_rows = [], 0
        self._last_seq = float(block.seq[-1])
        self._pending.append(block)
        self._pending_rows += len(block)
        limit = int(MAX_MOVE_S * self._rate_hz)
        while self._pending_rows > limit and len(self._pending) > 1:
            self._pending_rows -= len(self._pending.pop(0))
            self._truncated = True

    def captured(self, index: int, result: PoseResult) -> None:
        """Pose ``index`` was captured: the move that led to it is complete."""
        still = _Still(
            index, self._epoch, result.first_seq, result.last_seq, result.summary.accel_mean
        )
        samples = SampleBlock.concat(self._pending)
        previous = self._still
        if previous is not None:
            self.moves.append(self._move(previous, still, samples))
        tail = samples[samples.seq >= still.last_seq]
        self._pending = [tail] if len(tail) else []
        self._pending_rows = len(tail)
        self._truncated = False
        self._still = still

    def _move(self, before: _Still, after: _Still, samples: SampleBlock) -> RecordedMove:
        unusable = None
        if before.epoch != after.epoch:
            unusable = "the stream restarted during the move (the unit was reconnected)"
        elif self._truncated:
            unusable = f"the move took longer than {MAX_MOVE_S:g} s"
        span = samples[(samples.seq >= before.last_seq) & (samples.seq <= after.first_seq)]
        ends = (before.last_seq, after.first_seq)
        if unusable is None and (not len(span) or (span.seq[0], span.seq[-1]) != ends):
            unusable = "samples lost at the start or the end of the move"
        if unusable is not None:
            span = SampleBlock.empty()
        return RecordedMove(
            before=before.index,
            after=after.index,
            seq=span.seq.copy(),
            gyro_dps=span.gyro.copy(),
            accel_counts=span.accel.copy(),
            mean_before=before.accel_mean,
            mean_after=after.accel_mean,
            unusable=unusable,
        )

    def times(self, move: RecordedMove) -> FloatArray:
        """A move's sample times in device seconds (sequence numbers over the rate)."""
        return np.asarray(move.seq / self._rate_hz, dtype=np.float64)
