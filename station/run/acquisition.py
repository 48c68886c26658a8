"""Taking one still pose from a streaming putter: the live still-window detector, the
acquisition, and why a pose could not be taken.

The judging itself (:func:`station.domain.signals.stillness.judge_window`, its thresholds and its
verdict) lives in the domain, so that a recorded stream is segmented by the same code
(:func:`station.domain.signals.stillness.still_segments`). Live, :class:`StillnessDetector` feeds
it the driver's blocks; with adaptive capture (:mod:`station.domain.product.capture_budget`) a
still window grows, judged whole at every hop, until its mean's standard error meets the
budget or it reaches the ceiling. :class:`PoseAcquisition` takes one pose without
blocking; its result (:class:`PoseResult`) carries the accepted window's summary
(:class:`station.domain.signals.samples.WindowSummary`, computed once, by the judge).

::

    CalstationError
    └── AcquisitionError        no trustworthy still window for this pose
        ├── NotStillError       the unit kept moving until the timeout
        ├── LinkQualityError    too many samples lost on the link
        └── SaturatedAxisError  an accelerometer axis sits at an ADC rail while still
"""

import time
from dataclasses import dataclass

from station.device import DeviceTimeoutError, LinkCounters, PutterDriver
from station.domain.errors import CalstationError
from station.domain.product.capture_budget import WindowPolicy
from station.domain.signals.samples import SampleBlock, WindowSummary
from station.domain.signals.stillness import (
    SpreadScreen,
    StillnessThresholds,
    WindowVerdict,
    judge_window,
)

__all__ = [
    "AcquisitionError",
    "LinkQualityError",
    "NotStillError",
    "PoseAcquisition",
    "PoseResult",
    "SaturatedAxisError",
    "StillnessDetector",
    "StillnessThresholds",
    "WindowVerdict",
    "acquire_pose",
    "judge_window",
]


class AcquisitionError(CalstationError):
    """No trustworthy still window could be taken for a pose."""

    def __init__(self, message: str, pose: str | None = None) -> None:
        super().__init__(f"pose {pose}: {message}" if pose else message)
        self.pose = pose


class NotStillError(AcquisitionError):
    """The unit never stayed still for a whole window before the timeout."""


class LinkQualityError(AcquisitionError):
    """The windows lost more samples on the link than the limit allows."""


class SaturatedAxisError(AcquisitionError):
    """An accelerometer axis sits at 0 or 4095 counts while the unit is still."""

    def __init__(self, message: str, axes: tuple[str, ...], pose: str | None = None) -> None:
        super().__init__(message, pose)
        self.axes = axes


class StillnessDetector:
    """Feed it sample blocks as they arrive; it returns the first still window.

    Blocks are as the driver hands them out (accelerometer in counts). :attr:`last` is
    the latest verdict, for telling the operator what keeps the pose from being taken.

    How long a window is follows ``policy``
    (:class:`station.domain.product.capture_budget.WindowPolicy`;
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
        screen: SpreadScreen | None = None
        while self._next_eval <= self.samples_seen:
            end = self._next_eval
            start = max(self._start, end - ceiling)
            if end + hop <= self.samples_seen:  # a later window is judged in this feed too
                # Only the latest verdict is kept (:attr:`last`): a window the judge would
                # certainly refuse for its spread need not be judged (a quarter
                # second's feed holds four windows, each a thousand samples judged whole).
                screen = screen or SpreadScreen(
                    self._held.accel, self.limits.accel_std_max_counts, self.limits.sensor.adc_max
                )
                if screen.refuses(start - self._held_from, end - self._held_from):
                    self._start = end + hop - floor
                    self._next_eval = end + hop
                    continue
            window = self._held[start - self._held_from : end - self._held_from]
            verdict = judge_window(window, self.limits)
            self.last = verdict
            if verdict.still and self.policy.enough(verdict.summary.accel_std, len(window)):
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


@dataclass(frozen=True)
class PoseResult:
    """One still pose as the acquisition took it.

    ``summary`` is the accepted window's (:class:`station.domain.signals.samples.WindowSummary`:
    means, standard deviations and count; accelerometer in ADC counts, gyros in deg/s,
    temperature in °C). ``first_seq`` and ``last_seq`` are the window's sequence numbers;
    ``duration_s`` its span and ``wait_s`` the time from the start of the acquisition to
    its last sample, both in device time (sequence numbers over the sample rate);
    ``loss_fraction`` the samples the window lost, and ``link`` what happened on the link
    during the acquisition.
    """

    pose: str | None
    summary: WindowSummary
    first_seq: int
    last_seq: int
    duration_s: float
    wait_s: float
    loss_fraction: float
    link: LinkCounters

    @classmethod
    def accepted(
        cls,
        verdict: WindowVerdict,
        *,
        pose: str | None,
        rate_hz: float,
        wait_s: float,
        link: LinkCounters,
    ) -> "PoseResult":
        """The pose of a still window, with the summary its verdict was judged on."""
        window = verdict.window
        return cls(
            pose=pose,
            summary=verdict.summary,
            first_seq=int(window.seq[0]),
            last_seq=int(window.seq[-1]),
            duration_s=window.span / rate_hz,
            wait_s=wait_s,
            loss_fraction=verdict.loss_fraction,
            link=link,
        )


class PoseAcquisition:
    """Takes one pose without blocking: call :meth:`poll` from the interface's loop.

    The driver must already be streaming raw samples. Samples numbered below
    ``from_seq`` (taken before the operator was asked to move, say) are skipped.
    ``timeout_s`` is device time (samples over the rate), so a faster-than-real-time
    simulator times out just as a real unit would; ``stall_s`` is wall-clock time
    without any sample at all.
    """

    def __init__(
        self,
        driver: PutterDriver,
        *,
        pose: str | None = None,
        limits: StillnessThresholds | None = None,
        timeout_s: float = 30.0,
        stall_s: float = 2.0,
        from_seq: int = 0,
        policy: WindowPolicy | None = None,
    ) -> None:
        self.driver = driver
        self.from_seq = from_seq
        self.pose = pose
        self.detector = StillnessDetector(limits, policy)
        self.timeout_s = timeout_s
        self.stall_s = stall_s
        self._rate = driver.rate_hz
        self._first_seq: float | None = None
        self._last_seq: float | None = None
        self._stats0 = driver.stats
        self._last_arrival = time.monotonic()
        self.result: PoseResult | None = None
        #: The samples the latest :meth:`poll` took in, for a live view of the unit.
        self.recent = SampleBlock.empty()

    @property
    def elapsed_s(self) -> float:
        """Device time since the first sample of this acquisition."""
        if self._first_seq is None or self._last_seq is None:
            return 0.0
        return (self._last_seq - self._first_seq + 1) / self._rate

    @property
    def last_verdict(self) -> WindowVerdict | None:
        """The latest window's verdict: what keeps the pose from being taken."""
        return self.detector.last

    def poll(self) -> PoseResult | None:
        """Take in the samples received so far; return the pose once a window is still.

        Raises :class:`SaturatedAxisError` as soon as a window is still but for an
        axis at a rail, :class:`NotStillError` or :class:`LinkQualityError` at the
        timeout, :class:`~station.device.DeviceTimeoutError` when samples stop
        coming, and the driver's own errors (e.g. disconnection).
        """
        if self.result is not None:
            return self.result
        block = self.driver.drain()
        self.recent = block
        now = time.monotonic()
        if not len(block):
            if now - self._last_arrival > self.stall_s:
                raise DeviceTimeoutError(
                    f"pose {self.pose}: no samples from {self.driver.url} for {self.stall_s:g} s"
                )
            return None
        self._last_arrival = now
        block = block[block.seq >= self.from_seq]
        if not len(block):
            return None
        if self._first_seq is None:
            self._first_seq = float(block.seq[0])
        self._last_seq = float(block.seq[-1])
        verdict = self.detector.feed(block)
        if verdict is None:
            self._check(self.detector.last)
            return None
        # Waited until the window's last sample, not the last one drained: how many
        # samples one poll takes in depends on how busy the machine is.
        window = verdict.window
        self.result = PoseResult.accepted(
            verdict,
            pose=self.pose,
            rate_hz=self._rate,
            wait_s=(window.seq[-1] - self._first_seq + 1) / self._rate,
            link=self.driver.stats - self._stats0,
        )
        return self.result

    def _check(self, verdict: WindowVerdict | None) -> None:
        if verdict is None:
            return
        if verdict.saturated_axes and not verdict.motion:
            raise SaturatedAxisError(
                f"accelerometer {', '.join(verdict.saturated_axes)} saturated "
                "(stuck at the ADC rail while the unit is still)",
                verdict.saturated_axes,
                self.pose,
            )
        if self.elapsed_s < self.timeout_s:
            return
        summary = "; ".join(verdict.reasons)
        if not verdict.motion and verdict.loss_fraction > self.detector.limits.max_loss_fraction:
            raise LinkQualityError(f"bad link after {self.timeout_s:g} s: {summary}", self.pose)
        raise NotStillError(f"not still after {self.timeout_s:g} s: {summary}", self.pose)


def acquire_pose(
    driver: PutterDriver,
    *,
    pose: str | None = None,
    limits: StillnessThresholds | None = None,
    timeout_s: float = 30.0,
    poll_s: float = 0.02,
    from_seq: int = 0,
    policy: WindowPolicy | None = None,
) -> PoseResult:
    """Blocking form of :class:`PoseAcquisition`, for scripts and tests."""
    acquisition = PoseAcquisition(
        driver, pose=pose, limits=limits, timeout_s=timeout_s, from_seq=from_seq, policy=policy
    )
    while (result := acquisition.poll()) is None:
        time.sleep(poll_s)
    return result
