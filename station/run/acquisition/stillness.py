"""The live still-window detector: feeds the driver's blocks to the domain's judge.

The judging itself (:func:`station.domain.stillness.judge_window`, its thresholds and its
verdict) lives in the domain, so that a recorded stream is segmented by the same code
(:func:`station.domain.stillness.still_segments`). With adaptive capture
(:mod:`station.domain.capture_budget`) a still window grows, judged whole at every hop, until
its mean's standard error meets the budget or it reaches the ceiling.
"""

from station.domain.capture_budget import WindowPolicy
from station.domain.samples import SampleBlock
from station.domain.stillness import StillnessThresholds, WindowVerdict, judge_window

__all__ = ["StillnessDetector", "StillnessThresholds", "WindowVerdict", "judge_window"]


class StillnessDetector:
    """Feed it sample blocks as they arrive; it returns the first still window.

    Blocks are as the driver hands them out (accelerometer in counts). :attr:`last` is
    the latest verdict, for telling the operator what keeps the pose from being taken.

    How long a window is follows ``policy`` (:class:`station.domain.capture_budget.WindowPolicy`;
    by default every window is ``window_samples`` long). Every ``hop_samples`` the
    window from its start to the latest sample is judged whole: refused, the next one is
    the trailing ``floor`` samples; still but not yet enough (its mean's standard error
    above the budget, below the ceiling), it grows by a hop; still and enough, it is the
    pose's. With floor = ceiling this is the fixed trailing window.
    """

    def __init__(
        self, limits: StillnessThresholds | None = None, policy: WindowPolicy | None = None
    ) -> None:
        self.limits = limits or StillnessThresholds()
        self.policy = policy or WindowPolicy.fixed(self.limits.window_samples)
        self.last: WindowVerdict | None = None
        self.samples_seen = 0
        self._held = SampleBlock.empty()
        #: Sample number (counted from the first fed) of ``_held``'s first row.
        self._held_from = 0
        #: Where the window being grown starts (same count).
        self._start = 0
        self._next_eval = self.policy.floor

    def feed(self, block: SampleBlock) -> WindowVerdict | None:
        """Add samples; return the verdict of the first still window they complete, if any."""
        floor, ceiling = self.policy.floor, self.policy.ceiling
        hop = self.limits.hop_samples
        self._held = SampleBlock.concat((self._held, block)) if len(self._held) else block
        self.samples_seen += len(block)
        while self._next_eval <= self.samples_seen:
            end = self._next_eval
            start = max(self._start, end - ceiling)
            window = self._held[start - self._held_from : end - self._held_from]
            verdict = judge_window(window, self.limits)
            self.last = verdict
            if verdict.still and self.policy.enough(verdict.accel_std, len(window)):
                # The next window starts where this one ended.
                self._start = end
                self._next_eval = end + floor
                self._trim(end)
                return verdict
            if not verdict.still:
                self._start = end + hop - floor
            self._next_eval = end + hop
        self._trim(max(self._start, self.samples_seen - ceiling - hop))
        return None

    def _trim(self, keep_from: int) -> None:
        """Drop the held samples before sample ``keep_from``."""
        if keep_from > self._held_from:
            self._held = self._held[keep_from - self._held_from :]
            self._held_from = keep_from
