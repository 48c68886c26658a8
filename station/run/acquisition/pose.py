"""Taking one pose: stream samples until a still window, and summarise it."""

import time
from dataclasses import dataclass
from typing import Any

from station.device import DeviceTimeoutError, LinkStats, PutterDriver
from station.domain.arrays import FloatArray
from station.domain.capture_budget import WindowPolicy
from station.domain.samples import SampleBlock
from station.run.acquisition.errors import LinkQualityError, NotStillError, SaturatedAxisError
from station.run.acquisition.stillness import StillnessDetector, StillnessThresholds, WindowVerdict


@dataclass(frozen=True)
class PoseResult:
    """The record of one still pose.

    Means, standard deviations and the sample count are over the accepted window:
    accelerometer in ADC counts, gyros in deg/s, temperature in °C. ``duration_s`` is
    the window's span and ``wait_s`` the time from the start of the acquisition to
    the window's last sample, both in device time (sequence numbers over the sample rate);
    ``link`` counts what happened on the link during the acquisition.
    """

    pose: str | None
    accel_mean: FloatArray
    accel_std: FloatArray
    gyro_mean: FloatArray
    gyro_std: FloatArray
    temperature_c: float
    temperature_std_c: float
    sample_count: int
    first_seq: int
    last_seq: int
    duration_s: float
    wait_s: float
    loss_fraction: float
    link: LinkStats

    @classmethod
    def from_window(
        cls,
        window: SampleBlock,
        *,
        pose: str | None,
        rate_hz: float,
        wait_s: float,
        link: LinkStats,
        loss_fraction: float,
    ) -> "PoseResult":
        """Summarise an accepted window."""
        summary = window.summary()
        return cls(
            pose=pose,
            accel_mean=summary.accel_mean,
            accel_std=summary.accel_std,
            gyro_mean=summary.gyro_mean,
            gyro_std=summary.gyro_std,
            temperature_c=summary.temperature_c,
            temperature_std_c=summary.temperature_std_c,
            sample_count=summary.count,
            first_seq=int(window.seq[0]),
            last_seq=int(window.seq[-1]),
            duration_s=window.span / rate_hz,
            wait_s=wait_s,
            loss_fraction=loss_fraction,
            link=link,
        )

    def to_dict(self) -> dict[str, Any]:
        """Plain values for JSON."""
        return {
            "pose": self.pose,
            "accel_mean": self.accel_mean.tolist(),
            "accel_std": self.accel_std.tolist(),
            "gyro_mean": self.gyro_mean.tolist(),
            "gyro_std": self.gyro_std.tolist(),
            "temperature_c": self.temperature_c,
            "temperature_std_c": self.temperature_std_c,
            "sample_count": self.sample_count,
            "first_seq": self.first_seq,
            "last_seq": self.last_seq,
            "duration_s": self.duration_s,
            "wait_s": self.wait_s,
            "loss_fraction": self.loss_fraction,
            "link": self.link.to_dict(),
        }


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
        self.result = PoseResult.from_window(
            window,
            pose=self.pose,
            rate_hz=self._rate,
            wait_s=(window.seq[-1] - self._first_seq + 1) / self._rate,
            link=self.driver.stats - self._stats0,
            loss_fraction=verdict.loss_fraction,
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
