"""The pose being taken: its acquisition, the live view, and when it is accepted.

:class:`PoseCapture` holds what the station knows while it asks for one pose: the
samples of the last quarter second (the live view the operator watches), how many of
them lay still in the pose asked for (the capture's share), whether the unit moved since
the last capture, and which wrong place was named already. It polls
:class:`station.run.acquisition.PoseAcquisition` and hands over a captured window only
when the unit lies in the pose asked for, away from every pose taken before; what is
done with it is :class:`station.run.unit_run.UnitRun`'s business.
"""

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from station.device import PutterDriver
from station.domain.arrays import FloatArray as Array
from station.domain.i18n import tr
from station.domain.product.capture_budget import WindowPolicy
from station.domain.product.run_settings import RunSettings
from station.domain.signals.orientation import (
    Sensed,
    ZeroG,
    angle_deg,
    gravity_direction,
    sense,
)
from station.domain.signals.poses import POSES, Pose
from station.domain.signals.samples import SampleBlock
from station.results.journal import RunJournal
from station.run.acquisition import (
    LinkQualityError,
    NotStillError,
    PoseAcquisition,
    PoseResult,
    SaturatedAxisError,
    WindowVerdict,
    judge_window,
)
from station.run.messages import MessageLog
from station.run.operator_text import capture_refused, moved_early, pose_words

#: Samples of the live view: about a quarter second at the default rate.
LIVE_SAMPLES = 128
#: The topic of what is said about where the unit lies (a wrong pose, tilted, too close
#: to a pose taken): taken off the screen once it lies in the pose asked for.
WRONG_PLACE = "place"


@dataclass(frozen=True)
class LiveView:
    """What the operator sees while a pose is taken."""

    sensed: Sensed | None = None
    matches: bool = False
    accel_std: Array = field(default_factory=lambda: np.zeros(3))
    gyro_rate: Array = field(default_factory=lambda: np.zeros(3))
    moving: bool = True
    progress: float = 0.0
    #: Why the capture does not go on, in the operator's words (None: it does).
    refused: str | None = None


@dataclass(frozen=True)
class Saturated:
    """An axis sits at an ADC rail while the unit is still; ``verdict`` is that window."""

    verdict: WindowVerdict


class PoseCapture:
    """The acquisition of the pose asked for, and the live view of the unit meanwhile."""

    def __init__(
        self,
        settings: RunSettings,
        journal: RunJournal,
        messages: MessageLog,
        policy: WindowPolicy,
        on_samples: Callable[[SampleBlock], None] | None = None,
    ) -> None:
        self.settings = settings
        #: How long a still window is (fixed, or adaptive to the limits' budget).
        self.policy = policy
        #: Called with every block of samples drained (the gyro stream of a whole-unit run).
        self._on_samples = on_samples
        self._journal = journal
        self._messages = messages
        self._names = journal.poses
        self.live = LiveView()
        self._acquisition: PoseAcquisition | None = None
        self._recent = SampleBlock.empty()
        self._still_samples = 0
        self._wrong_pose_said: str | None = None
        #: What the poses taken tell of the offsets, and which captures told it.
        self._zero_g_of: tuple[tuple[int, object], ...] | None = None
        self._known_zero_g = ZeroG.datasheet(settings.sensor)
        #: The sequence number at which the live view first saw the unit move since the
        #: last capture (None: it has not; before it has, it still lies in the pose just
        #: taken, which is no mistake).
        self._moved_at: float | None = None

    def restart(self, driver: PutterDriver, target: Pose | None) -> None:
        """Start taking ``target`` afresh (after a capture, a refusal, a redo, a return)."""
        self._acquisition = PoseAcquisition(
            driver,
            pose=target.name if target else None,
            limits=self.settings.stillness,
            timeout_s=self.settings.pose_timeout_s,
            policy=self.policy,
        )

    def forget_window(self) -> None:
        """Drop the live window: the unit was away, its samples are no longer the unit's."""
        self._recent = SampleBlock.empty()

    def clear_view(self) -> None:
        """Show nothing live any more (the run ended)."""
        self.live = LiveView()

    def poll(self, driver: PutterDriver, index: int, target: Pose) -> PoseResult | Saturated | None:
        """Act on the samples received: the accepted pose, a saturated axis, or nothing yet."""
        if self._acquisition is None:
            self.restart(driver, target)
        acquisition = self._acquisition
        assert acquisition is not None
        try:
            try:
                result = acquisition.poll()
            finally:
                if self._on_samples is not None:
                    self._on_samples(acquisition.recent)
        except SaturatedAxisError:
            verdict = acquisition.last_verdict
            assert verdict is not None  # the error comes from a judged window
            return Saturated(verdict)
        except (NotStillError, LinkQualityError) as exc:
            self._messages.say("warn", str(exc))
            self.restart(driver, target)
            return None
        saturated = self._update_live(acquisition.recent, index, target)
        if saturated is not None:
            return saturated
        if result is None and self.live.matches and self.live.progress >= 1.0:
            refused = capture_refused(acquisition.last_verdict, self.settings.stillness)
            self.live = replace(self.live, refused=refused)
        if result is None:
            if not self.live.matches:
                self.restart(driver, target)
            return None
        if not self._acceptable(result, index, target):
            self.restart(driver, target)
            return None
        self._wrong_pose_said = None
        self._moved_at = None
        self._still_samples = 0
        self.live = LiveView()
        return result

    def _update_live(self, block: SampleBlock, index: int, target: Pose) -> Saturated | None:
        """Judge every sample drained, in windows of :data:`LIVE_SAMPLES` oldest first.

        The newest window ends at the newest sample, each earlier one where the next
        begins, back to the first sample new to the view (the oldest window reaches
        into the samples seen before, to be whole): a move made and finished between
        two polls is seen, however many samples a poll takes in. The screen shows the
        newest window.
        """
        if len(block) == 0:
            return None
        held = SampleBlock.concat((self._recent, block))
        self._recent = held[-LIVE_SAMPLES:]
        seen = len(held) - len(block)
        ends = range(len(held), seen, -LIVE_SAMPLES)[::-1]
        for start, end in zip((seen, *ends[:-1]), ends, strict=True):
            window = held[max(0, end - LIVE_SAMPLES) : end]
            saturated = self._judge_live(window, end - start, index, target)
            if saturated is not None:
                return saturated
        return None

    def _judge_live(
        self, window: SampleBlock, new: int, index: int, target: Pose
    ) -> Saturated | None:
        """Update the live view on one window whose last ``new`` samples are new to it."""
        verdict: WindowVerdict = judge_window(window, self.settings.stillness)
        summary = verdict.summary
        sensed = sense(summary.accel_mean, zero_g=self._zero_g())
        if verdict.saturated_axes and not verdict.motion and len(window) == LIVE_SAMPLES:
            return Saturated(verdict)
        matches = sensed.matches(target, self.settings.pose_tolerance_deg)
        was_capturing = self.live.progress >= 0.25
        if verdict.motion and self._moved_at is None:
            self._moved_at = float(window.seq[-1])
        refused = self.live.refused if self._still_samples else None
        if matches and not verdict.motion:
            self._still_samples += new
            if self._wrong_pose_said is not None:  # what was said of the place is past
                self._wrong_pose_said = None
                self._messages.unsay(WRONG_PLACE)
        else:
            if was_capturing and matches:
                name = pose_words(target.name)
                said = tr("moved during capture of {pose}: hold the putter still", pose=name)
                self._messages.say("warn", said)
            elif self.live.progress >= 0.05 and self.live.matches:  # not the settling
                refused = moved_early()
            self._still_samples = 0
        if self._moved_at is not None and not matches and not verdict.motion:
            self._say_wrong_pose(sensed, index, target)
        self.live = LiveView(
            sensed=sensed,
            matches=matches,
            accel_std=summary.accel_std,
            gyro_rate=summary.gyro_mean,
            moving=verdict.motion,
            progress=min(1.0, self._still_samples / self.policy.samples_needed(summary.accel_std)),
            refused=refused,
        )
        return None

    def _acceptable(self, result: PoseResult, index: int, target: Pose) -> bool:
        """Whether the still window lies in ``target``, away from every pose taken.

        A window refused is said to the operator only when the unit had moved before it:
        a poll takes in a pass's samples (a quarter second, or seconds of a sped-up
        simulator's), and a window from before a move the same poll saw is the unit still
        lying in the pose just taken, which is no mistake.
        """
        sensed = sense(result.summary.accel_mean, zero_g=self._zero_g())
        close_to_earlier = any(
            angle_deg(direction, sensed.direction) < self.settings.min_pose_separation_deg
            for _, direction in self._captured_directions()
        )
        if close_to_earlier or not sensed.matches(target, self.settings.pose_tolerance_deg):
            if self._moved_at is not None and self._moved_at < result.first_seq:
                self._say_wrong_pose(sensed, index, target)
            return False
        return True

    def _say_wrong_pose(self, sensed: Sensed, index: int, target: Pose) -> None:
        """Say once per place why the unit lying still there is not captured."""
        if self._wrong_pose_said == sensed.nearest.name:
            return
        self._wrong_pose_said = sensed.nearest.name
        for j, direction in self._captured_directions():
            if angle_deg(direction, sensed.direction) < self.settings.min_pose_separation_deg:
                self._messages.say(
                    "warn",
                    tr(
                        "too close to pose {taken} ({taken_pose}), already taken: "
                        "pose {number} is {pose}",
                        taken=j + 1,
                        taken_pose=pose_words(self._names[j]),
                        number=index + 1,
                        pose=pose_words(target.name),
                    ),
                    topic=WRONG_PLACE,
                )
                return
        if sensed.nearest.name == target.name:  # the right pose, too far tilted
            self._messages.say(
                "warn",
                tr(
                    "tilted: the putter lies {angle}° from {pose} ({allowed}° allowed): "
                    "lay it flat in its cradle",
                    angle=f"{sensed.nearest_deg:.0f}",
                    pose=pose_words(target.name),
                    allowed=f"{self.settings.pose_tolerance_deg:.0f}",
                ),
                topic=WRONG_PLACE,
            )
            return
        self._messages.say(
            "warn",
            tr(
                "wrong pose: the putter lies {lies}, pose {number} is {pose}",
                lies=pose_words(sensed.nearest.name),
                number=index + 1,
                pose=pose_words(target.name),
            ),
            topic=WRONG_PLACE,
        )

    def _captured_means(self) -> list[tuple[int, Array]]:
        """Mean counts of every pose taken, by pose index."""
        return [
            (i, np.array(c.record.mean.as_tuple()))
            for i, c in sorted(self._journal.captures.items())
        ]

    def _zero_g(self) -> ZeroG:
        """Each axis' zero-g counts as the poses taken so far measured them (worked out
        again only when the captures change: the live view asks at every tick)."""
        taken = tuple((i, c.captured_at) for i, c in self._journal.captures.items())
        if taken != self._zero_g_of:
            self._zero_g_of = taken
            self._known_zero_g = ZeroG.measured(
                ((POSES[self._names[i]], mean) for i, mean in self._captured_means()),
                self.settings.sensor,
            )
        return self._known_zero_g

    def _captured_directions(self) -> list[tuple[int, Array]]:
        """Sensed gravity direction of every pose taken, by pose index."""
        zero_g = self._zero_g()
        return [(i, gravity_direction(mean, zero_g)) for i, mean in self._captured_means()]
