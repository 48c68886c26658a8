"""One unit's calibration run: poses, solve, verification, write-back, verdict.

:class:`UnitRun` is the station's logic without a screen or a keyboard. The interface
calls :meth:`UnitRun.step` from its own loop (it never blocks for long: it drains the
samples received so far and acts on them), shows :attr:`UnitRun.view`, and passes the
operator's keys on as :meth:`redo`, :meth:`redo_last` and :meth:`abort`.

A pose is captured only when the unit lies in the pose asked for and a whole window
of samples is still (:mod:`station.acquisition`). After the fit poses the station
solves (:mod:`station.calibration`), asks for the verification pose, checks its
calibrated |g|, writes the coefficients into the unit, reads them back, and checks the
unit's own calibrated output. Every check is against the limits profile
(:mod:`station.limits`); the run ends with a :class:`station.records.RunRecord`.
The journal is saved after every pose, so a crash loses nothing.
"""

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime
from enum import StrEnum

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from station import __version__
from station.acquisition.errors import LinkQualityError, NotStillError, SaturatedAxisError
from station.acquisition.pose import PoseAcquisition, PoseResult
from station.acquisition.stillness import StillnessThresholds, WindowVerdict, judge_window
from station.arrays import FloatArray as Array
from station.calibration import CalibrationError, Model, Solution, apply, solve
from station.device import (
    DeviceCalibration,
    DeviceDisconnectedError,
    DeviceError,
    DeviceTimeoutError,
    PutterDriver,
    SerialNumberMismatchError,
)
from station.gyro import summarize_still_poses
from station.journal import Capture, JournalFile, RunJournal
from station.limits import LimitsProfile, check
from station.operator_text import (
    MOVED_EARLY,
    capture_refused,
    port_problem,
    pose_words,
    wrong_unit,
)
from station.orientation import POSE_TOLERANCE_DEG, Sensed, angle_deg, gravity_direction, sense
from station.pose_plan import check_plan
from station.poses import CALIBRATION_POSES, POSES, VERIFICATION_POSE, Pose, pose
from station.records import (
    Coefficients,
    FailureReason,
    GyroSummary,
    LinkStats,
    PoseRecord,
    QualityMetrics,
    ReplacedCapture,
    RunRecord,
    Vector3,
)
from station.run_checks import run_checks

ALGORITHM = "autocal-eq10"
#: Samples of the live view: about a quarter second at the default rate.
LIVE_SAMPLES = 128
#: Calibrated samples averaged to check the unit's own output.
UNIT_OUTPUT_SAMPLES = 256
#: Wall-clock seconds between attempts to reach a unit whose cable was pulled.
RECONNECT_EVERY_S = 0.5
#: Wall-clock seconds without a sample before the unit counts as gone.
STALL_S = 2.0


class RunSettings(BaseModel):
    """How a station runs its units (from the station's configuration)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    poses: tuple[str, ...] = Field(CALIBRATION_POSES, min_length=6)
    verification_pose: str = VERIFICATION_POSE
    pose_tolerance_deg: float = Field(POSE_TOLERANCE_DEG, gt=0, lt=90)
    min_pose_separation_deg: float = Field(
        30.0, gt=0, description="a capture this close to an earlier pose is refused"
    )
    stillness: StillnessThresholds = StillnessThresholds()
    pose_timeout_s: float = Field(30.0, gt=0, description="device time before 'not still'")
    model: Model = "six"

    @field_validator("poses", "verification_pose")
    @classmethod
    def _known_poses(cls, value: str | tuple[str, ...]) -> str | tuple[str, ...]:
        names = (value,) if isinstance(value, str) else value
        unknown = [n for n in names if n not in POSES]
        if unknown:
            raise ValueError(f"unknown pose {unknown[0]!r}; known: {', '.join(POSES)}")
        return value

    @model_validator(mode="after")
    def _can_finish(self) -> "RunSettings":
        check_plan(self.poses, self.verification_pose, self.min_pose_separation_deg, self.model)
        return self


class Phase(StrEnum):
    """Where the run stands."""

    POSE = "pose"
    RECONNECT = "reconnect"
    UNIT_OUTPUT = "unit_output"
    DONE = "done"


@dataclass
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
class Message:
    """A sentence for the operator; ``level`` is info, warn or error.

    ``topic`` names a condition the message is about (``link``): it is taken off the
    screen when the condition ends.
    """

    level: str
    text: str
    topic: str | None = None


def _vec(values: Array | tuple[float, float, float]) -> Vector3:
    return Vector3(x=float(values[0]), y=float(values[1]), z=float(values[2]))


def _now() -> datetime:
    return datetime.now(UTC)


class UnitRun:
    """The calibration of one unit, driven step by step by the interface."""

    def __init__(
        self,
        *,
        driver: PutterDriver,
        journal: RunJournal,
        journal_file: JournalFile,
        profile: LimitsProfile,
        settings: RunSettings,
        reopen: Callable[[], PutterDriver],
    ) -> None:
        self.driver = driver
        self.journal = journal
        self.journal_file = journal_file
        self.profile = profile
        self.settings = settings
        self._reopen = reopen
        self.sequence: tuple[Pose, ...] = tuple(pose(n) for n in journal.poses)
        self.phase = Phase.POSE
        self.index = journal.next_pose
        self.live = LiveView()
        self.messages: deque[Message] = deque(maxlen=6)
        #: Messages said so far (the deque keeps only the latest).
        self.said = 0
        self.solution: Solution | None = None
        self.record: RunRecord | None = None
        self._acquisition: PoseAcquisition | None = None
        self._recent: Array = np.empty((0, 8))
        self._still_samples = 0
        self._failures: list[FailureReason] = []
        self._unit_output: list[Array] = []
        self._next_reconnect = 0.0
        self._last_arrival = 0.0
        #: The live window that failed the unit before its pose was captured.
        self._evidence: PoseRecord | None = None
        self._wrong_pose_said: str | None = None
        #: Whether the unit moved since the last capture (before it has, it still lies
        #: in the pose just taken, which is no mistake).
        self._moved = False
        self.verification_error_mg: float | None = None
        self.unit_output_error_mg: float | None = None
        #: Whether the coefficients are in the unit (written and read back).
        self.written = False
        #: The serial of another unit plugged in while this one was awaited.
        self.wrong_unit: str | None = None

    # -- what the interface shows --------------------------------------------------

    @property
    def fit_count(self) -> int:
        """Number of poses that feed the solve."""
        return len(self.settings.poses)

    @property
    def requested(self) -> Pose | None:
        """The pose asked for now (None once all are taken)."""
        return self.sequence[self.index] if self.index < len(self.sequence) else None

    def say(self, level: str, text: str, topic: str | None = None) -> None:
        """Tell the operator something (newest last)."""
        self.messages.append(Message(level, text, topic))
        self.said += 1

    def unsay(self, topic: str) -> None:
        """Take the messages about ``topic`` off the screen: it is no longer true."""
        kept = [m for m in self.messages if m.topic != topic]
        self.messages.clear()
        self.messages.extend(kept)

    # -- operator commands -----------------------------------------------------------

    def redo(self, index: int) -> None:
        """Take pose ``index`` again; its current capture is kept for audit."""
        if not 0 <= index < len(self.sequence):
            return
        if index not in self.journal.captures:
            name = pose_words(self.sequence[index].name)
            self.say("warn", f"pose {index + 1} ({name}) is not taken yet: nothing to redo")
            return
        if self.phase not in (Phase.POSE, Phase.RECONNECT):
            self.say("warn", "too late to redo a pose: the coefficients are being written")
            return
        capture = self.journal.captures.pop(index, None)
        if capture is not None:
            rec = capture.record
            self.journal.replaced.setdefault(index, []).append(
                ReplacedCapture(
                    captured_at=capture.captured_at,
                    reason="redone by the operator",
                    mean=rec.mean,
                    std=rec.std,
                    sample_count=rec.sample_count,
                )
            )
            self.journal_file.save(self.journal)
        self.solution = None
        self.index = self.journal.next_pose
        self._restart_acquisition()
        name = pose_words(self.sequence[index].name)
        self.say("info", f"pose {index + 1} ({name}) will be taken again")

    def redo_last(self) -> None:
        """Take the most recently captured pose again."""
        if self.journal.captures:
            last = max(self.journal.captures, key=lambda i: self.journal.captures[i].captured_at)
            self.redo(last)

    def abort(self) -> RunRecord | None:
        """Stop this unit. With poses taken, the run is recorded as failed ("aborted")."""
        if self.phase is Phase.DONE:
            return self.record
        self._failures = [FailureReason(code="aborted", message="aborted by the operator")]
        if self.written:  # the unit holds them: not an abort that left it as it was
            self._failures = [
                FailureReason(
                    code="unit_output",
                    message="aborted by the operator after the coefficients were written: "
                    "the unit's own output was not checked",
                )
            ]
        self._finish(store=bool(self.journal.captures))
        return self.record

    # -- the loop ----------------------------------------------------------------------

    def step(self) -> None:
        """Act on the samples received since the last step."""
        try:
            if self.phase is Phase.POSE:
                self._step_pose()
            elif self.phase is Phase.RECONNECT:
                self._step_reconnect()
            elif self.phase is Phase.UNIT_OUTPUT:
                self._step_unit_output()
        except (DeviceDisconnectedError, DeviceTimeoutError) as exc:
            self._lost_link(exc)

    def _step_pose(self) -> None:
        target = self.requested
        if target is None:
            return
        if self._acquisition is None:
            self._restart_acquisition()
        acquisition = self._acquisition
        assert acquisition is not None
        try:
            result = acquisition.poll()
        except SaturatedAxisError:
            verdict = acquisition.last_verdict
            assert verdict is not None  # the error comes from a judged window
            self._fail_saturated(target, verdict)
            return
        except (NotStillError, LinkQualityError) as exc:
            self.say("warn", str(exc))
            self._restart_acquisition()
            return
        self._update_live(acquisition.recent, target)
        if self.phase is Phase.DONE:
            return
        if result is None and self.live.matches and self.live.progress >= 1.0:
            refused = capture_refused(acquisition.last_verdict, self.settings.stillness)
            self.live = replace(self.live, refused=refused)
        if result is None:
            if not self.live.matches:
                self._restart_acquisition()
            return
        self._accept(result, target)

    def _update_live(self, rows: Array, target: Pose) -> None:
        if len(rows) == 0:
            return
        self._recent = np.concatenate((self._recent, rows))[-LIVE_SAMPLES:]
        window = self._recent
        sensed = sense(window[:, 1:4].mean(axis=0))
        verdict: WindowVerdict = judge_window(window, self.settings.stillness)
        if verdict.saturated_axes and not verdict.motion and len(window) == LIVE_SAMPLES:
            self._fail_saturated(target, verdict)
            return
        matches = sensed.matches(target, self.settings.pose_tolerance_deg)
        was_capturing = self.live.progress >= 0.25
        if verdict.motion:
            self._moved = True
        refused = self.live.refused if self._still_samples else None
        if matches and not verdict.motion:
            self._still_samples += len(rows)
        else:
            if was_capturing and matches:
                name = pose_words(target.name)
                self.say("warn", f"moved during capture of {name}: hold the putter still")
            elif self.live.progress >= 0.05 and self.live.matches:  # not the settling
                refused = MOVED_EARLY
            self._still_samples = 0
        if self._moved and not matches and not verdict.motion:
            self._say_wrong_pose(sensed, target)
        self.live = LiveView(
            sensed=sensed,
            matches=matches,
            accel_std=window[:, 1:4].std(axis=0),
            gyro_rate=window[:, 4:7].mean(axis=0),
            moving=verdict.motion,
            progress=min(1.0, self._still_samples / self.settings.stillness.window_samples),
            refused=refused,
        )

    def _fail_saturated(self, target: Pose, verdict: WindowVerdict) -> None:
        """An axis sits at an ADC rail while the unit is still: the unit fails at once.

        The window that showed it is kept as the pose's record, as evidence.
        """
        window = verdict.window
        self._evidence = PoseRecord(
            index=self.index,
            name=target.name,
            role="verify" if self.index >= self.fit_count else "fit",
            mean=_vec(window[:, 1:4].mean(axis=0)),
            std=_vec(window[:, 1:4].std(axis=0, ddof=1)),
            sample_count=len(window),
            gyro_mean=_vec(window[:, 4:7].mean(axis=0)),
            temperature_c=float(window[:, 7].mean()),
        )
        axes = verdict.saturated_axes
        self._failures.append(
            FailureReason(
                code="saturated",
                message=f"accelerometer {', '.join(axes)} stuck at the ADC rail "
                "while the unit is still",
                pose=self.index,
                axis=axes[0] if len(axes) == 1 else None,
            )
        )
        self._finish(store=True)

    def _say_wrong_pose(self, sensed: Sensed, target: Pose) -> None:
        """Say once per place why the unit lying still there is not captured."""
        if self._wrong_pose_said == sensed.nearest.name:
            return
        self._wrong_pose_said = sensed.nearest.name
        for j, direction in self._captured_directions():
            if angle_deg(direction, sensed.direction) < self.settings.min_pose_separation_deg:
                self.say(
                    "warn",
                    f"too close to pose {j + 1} ({pose_words(self.sequence[j].name)}), "
                    f"already taken: pose {self.index + 1} is {pose_words(target.name)}",
                )
                return
        self.say(
            "warn",
            f"wrong pose: the putter lies {pose_words(sensed.nearest.name)}, "
            f"pose {self.index + 1} is {pose_words(target.name)}",
        )

    def _captured_directions(self) -> list[tuple[int, Array]]:
        """Sensed gravity direction of every pose taken, by pose index."""
        return [
            (i, gravity_direction(np.array(c.record.mean.as_tuple())))
            for i, c in sorted(self.journal.captures.items())
        ]

    def _restart_acquisition(self) -> None:
        target = self.requested
        self._acquisition = PoseAcquisition(
            self.driver,
            pose=target.name if target else None,
            limits=self.settings.stillness,
            timeout_s=self.settings.pose_timeout_s,
        )

    def _accept(self, result: PoseResult, target: Pose) -> None:
        sensed = sense(result.accel_mean)
        close_to_earlier = any(
            angle_deg(direction, sensed.direction) < self.settings.min_pose_separation_deg
            for _, direction in self._captured_directions()
        )
        if close_to_earlier or not sensed.matches(target, self.settings.pose_tolerance_deg):
            if self._moved:
                self._say_wrong_pose(sensed, target)
            self._restart_acquisition()
            return
        index = self.index
        role = "verify" if index >= self.fit_count else "fit"
        record = PoseRecord(
            index=index,
            name=target.name,
            role=role,
            mean=_vec(result.accel_mean),
            std=_vec(result.accel_std),
            sample_count=result.sample_count,
            gyro_mean=_vec(result.gyro_mean),
            temperature_c=result.temperature_c,
            link=LinkStats(
                crc_errors=result.link.crc_failures,
                gaps=result.link.seq_gaps,
                resyncs=result.link.resyncs,
                lost_samples=result.link.samples_lost,
            ),
            replaced=tuple(self.journal.replaced.get(index, ())),
        )
        self.journal.captures[index] = Capture(
            record=record,
            gyro_std=_vec(result.gyro_std),
            captured_at=_now(),
            duration_s=result.duration_s,
            loss_fraction=result.loss_fraction,
        )
        self.journal_file.save(self.journal)
        self.say("info", f"pose {index + 1} ({pose_words(target.name)}) captured")
        self._wrong_pose_said = None
        self._moved = False
        self._still_samples = 0
        self.live = LiveView()
        self.index = self.journal.next_pose
        if self.index >= self.fit_count and self.solution is None:
            self._solve()
        if self.phase is not Phase.POSE:
            return
        if self.index >= len(self.sequence):
            self._write_back()
        else:
            self._restart_acquisition()

    # -- after the poses ---------------------------------------------------------------

    def _fit_means(self) -> Array:
        return np.array(
            [self.journal.captures[i].record.mean.as_tuple() for i in range(self.fit_count)]
        )

    def _solve(self) -> None:
        try:
            self.solution = solve(self._fit_means(), self.settings.model)
        except CalibrationError as exc:
            pose_note = f" (pose {exc.pose + 1})" if exc.pose is not None else ""
            self._failures.append(
                FailureReason(code="calibration", message=f"{exc}{pose_note}", pose=exc.pose)
            )
            self._finish(store=True)
            return
        self.say("info", "calibration solved: now the verification pose")

    def _write_back(self) -> None:
        assert self.solution is not None
        cal = self.solution.calibration
        written = DeviceCalibration(cal.offset, cal.matrix)
        try:
            self.driver.stop_stream()
            self.driver.write_calibration(written)
            back = self.driver.read_calibration()
            self.written = True
        except DeviceError as exc:
            self._failures.append(
                FailureReason(code="writeback", message=f"write-back failed: {exc}")
            )
            self._finish(store=True)
            return
        scale = np.concatenate([np.abs(written.offset), np.abs(written.matrix).ravel()])
        diff = np.concatenate(
            [back.offset - written.offset, (back.matrix - written.matrix).ravel()]
        )
        relative = float(np.max(np.abs(diff) / np.where(scale > 0, scale, 1.0)))
        if (reason := check(self.profile, "writeback", relative)) is not None:
            self._failures.append(reason)
        self.driver.start_stream(calibrated=True)
        self._unit_output = []
        self._last_arrival = time.monotonic()
        self.phase = Phase.UNIT_OUTPUT
        self.say("info", "coefficients written and read back: checking the unit's own output")

    def _step_unit_output(self) -> None:
        rows = self.driver.drain_calibrated()
        now = time.monotonic()
        if len(rows):
            self._unit_output.append(rows)
            self._last_arrival = now
        elif now - self._last_arrival > STALL_S:
            raise DeviceTimeoutError(
                f"no calibrated samples from {self.driver.url} for {STALL_S:g} s"
            )
        got = np.concatenate(self._unit_output) if self._unit_output else np.empty((0, 4))
        if len(got) < UNIT_OUTPUT_SAMPLES:
            return
        self.driver.stop_stream()
        g = got[:UNIT_OUTPUT_SAMPLES, 1:4].mean(axis=0)
        self.unit_output_error_mg = abs(float(np.linalg.norm(g)) - 1.0) * 1000.0
        if (reason := check(self.profile, "unit_output", self.unit_output_error_mg)) is not None:
            self._failures.append(reason)
        self._finish(store=True)

    def _lost_link(self, exc: DeviceError) -> None:
        self.say(
            "error",
            f"lost the unit ({port_problem(exc)}): plug it back in, the poses taken are kept",
            topic="link",
        )
        self.driver.close()
        self.phase = Phase.RECONNECT
        self._next_reconnect = time.monotonic() + RECONNECT_EVERY_S

    def _step_reconnect(self) -> None:
        if time.monotonic() < self._next_reconnect:
            return
        self._next_reconnect = time.monotonic() + RECONNECT_EVERY_S
        try:
            driver = self._reopen()
        except SerialNumberMismatchError as exc:
            if self.wrong_unit != exc.reported:
                self.wrong_unit = exc.reported
                self.say("error", wrong_unit(exc.reported, exc.expected), topic="link")
            return
        except DeviceError:
            return
        self.driver = driver
        self.wrong_unit = None
        self.phase = Phase.POSE
        self._recent = np.empty((0, 8))
        self.unsay("link")
        self.say("info", "the unit is back: carry on")
        if self.index >= len(self.sequence):  # it went while its coefficients were written
            self._write_back()
        else:
            self._restart_acquisition()

    # -- the verdict -------------------------------------------------------------------

    def _checks(self) -> list[FailureReason]:
        calibration = self.solution.calibration if self.solution is not None else None
        result = run_checks(
            self.profile, self.journal.captures, calibration, self.fit_count, self._gyro_summary()
        )
        if result.verification_error_mg is not None:
            self.verification_error_mg = result.verification_error_mg
        return result.reasons

    def _gyro_summary(self) -> GyroSummary | None:
        """Bias and noise of each gyro over the fit poses, and their bias-vs-gravity slope."""
        fit = [
            self.journal.captures[i] for i in range(self.fit_count) if i in self.journal.captures
        ]
        gyro_means = [c.record.gyro_mean for c in fit]
        if not fit or any(m is None for m in gyro_means):
            return None
        means = np.array([m.as_tuple() for m in gyro_means if m is not None])
        stds = np.array([c.gyro_std.as_tuple() for c in fit])
        still = None
        if self.solution is not None and len(fit) == self.fit_count:
            gravity = apply(self.solution.calibration, self._fit_means())
            still = summarize_still_poses(means, stds, gravity)
        return GyroSummary(
            bias=_vec(means.mean(axis=0)),
            noise=_vec(np.sqrt((stds**2).mean(axis=0))),
            still=still,
        )

    def _pose_records(self) -> tuple[PoseRecord, ...]:
        """Every pose taken (plus the window that failed the unit, if not taken), in order.

        A run that ends with a pose missing (aborted after a redo) is numbered without
        the gap; the names still say which pose each one is.
        """
        taken = [self.journal.captures[i].record for i in sorted(self.journal.captures)]
        evidence = self._evidence
        if evidence is not None and evidence.index not in self.journal.captures:
            taken = sorted((*taken, evidence), key=lambda p: p.index)
        return tuple(
            p if p.index == i else p.model_copy(update={"index": i}) for i, p in enumerate(taken)
        )

    def _finish(self, *, store: bool) -> None:
        failures = self._checks() if not any(f.code == "aborted" for f in self._failures) else []
        failures = self._failures + [f for f in failures if f not in self._failures]
        self.phase = Phase.DONE
        self.live = LiveView()
        if not store:
            self.record = None
            return
        solution = self.solution
        coefficients = quality = None
        if solution is not None:
            cal = solution.calibration.to_dict()
            coefficients = Coefficients(
                offset=Vector3.model_validate(cal["offset"]),
                sensitivity=Vector3.model_validate(cal["sensitivity"]),
                matrix=tuple(tuple(row) for row in solution.calibration.matrix.tolist()),
            )
            q = solution.quality
            quality = QualityMetrics(
                residual_rms_mg=q.residual_rms_mg,
                residual_max_mg=q.residual_max_mg,
                condition_number=max(1.0, q.condition_number),
                verification_error_mg=self.verification_error_mg,
            )
        self.record = RunRecord(
            run_id=self.journal.run_id,
            serial=self.journal.serial,
            station_id=self.journal.station_id,
            operator_id=self.journal.operator_id,
            lot=self.journal.lot,
            started_at=self.journal.started_at,
            finished_at=_now(),
            software_version=__version__,
            algorithm=ALGORITHM if self.settings.model == "six" else "autocal-ls9",
            model=self.settings.model,
            limits=self.profile.ref,
            verdict="fail" if failures else "pass",
            failures=tuple(failures),
            coefficients=coefficients,
            quality=quality,
            gyro=self._gyro_summary(),
            poses=self._pose_records(),
        )
