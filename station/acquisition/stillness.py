"""The live still-window detector: feeds the driver's blocks to the domain's judge.

The judging itself (:func:`station.stillness.judge_window`, its thresholds and its
verdict) lives in the domain, so that a recorded stream is segmented by the same code
(:func:`station.stillness.still_segments`).
"""

from station.samples import SampleBlock
from station.stillness import StillnessThresholds, WindowVerdict, judge_window

__all__ = ["StillnessDetector", "StillnessThresholds", "WindowVerdict", "judge_window"]


class StillnessDetector:
    """Feed it sample blocks as they arrive; it returns the first still window.

    Blocks are as the driver hands them out (accelerometer in counts). :attr:`last` is
    the latest verdict, for telling the operator what keeps the pose from being taken.
    """

    def __init__(self, limits: StillnessThresholds | None = None) -> None:
        self.limits = limits or StillnessThresholds()
        self.last: WindowVerdict | None = None
        self.samples_seen = 0
        self._held = SampleBlock.empty()
        self._next_eval = self.limits.window_samples

    def feed(self, block: SampleBlock) -> WindowVerdict | None:
        """Add samples; return the verdict of the first still window they complete, if any."""
        width = self.limits.window_samples
        hop = self.limits.hop_samples
        start = self.samples_seen
        self._held = SampleBlock.concat((self._held, block)) if len(self._held) else block
        self.samples_seen += len(block)
        held_from = start - (len(self._held) - len(block))
        while self._next_eval <= self.samples_seen:
            end = self._next_eval - held_from
            verdict = judge_window(self._held[end - width : end], self.limits)
            self.last = verdict
            if verdict.still:
                # The next window starts where this one ended.
                self._next_eval += width
                self._held = self._held[end:]
                return verdict
            self._next_eval += hop
        keep = width + hop
        if len(self._held) > keep:
            self._held = self._held[-keep:]
        return None
