"""One unit's calibration run: poses, solve, verification, write-back, verdict.

:class:`UnitRun` is the station's logic without a screen or a keyboard. The interface
calls :meth:`UnitRun.step` from its own loop (it never blocks for long: it drains the
samples received so far and acts on them), draws :meth:`UnitRun.view`, and passes the
operator's keys on as :meth:`redo` and :meth:`abort`.

A pose is captured only when the unit lies in the pose asked for and a whole window
of samples is still (:mod:`station.run.capture`). After the fit poses the station
solves (:mod:`station.domain.calibration`), asks for the verification pose, writes the
coefficients into the unit and reads them back (:mod:`station.run.writeback`), and
checks the unit's own calibrated output (:mod:`station.run.unit_output`). Every check
is against the limits profile (:mod:`station.domain.product.limits`); the run ends with a
:class:`station.domain.record.records.RunRecord` (:mod:`station.run.record`). The journal is saved
after every pose, so a crash loses nothing.

:class:`UnitRun` holds the run's state machine (:mod:`station.run.phases`) and what
links the steps: the journal, the solution, the failures found. Each step's own state
lives in its module under :mod:`station.run`.
"""

from collections.abc import Callable

from station.device import (
    DeviceDisconnectedError,
    DeviceError,
    DeviceTimeoutError,
    PutterDriver,
)
from station.domain.arrays import FloatArray
from station.domain.calibration import CalibrationError, GeometryLimits, Solution, solve
from station.domain.gyro.motion import GyroMatrixError
from station.domain.i18n import tr
from station.domain.product.limits import LimitsProfile, check
from station.domain.product.run_settings import RunSettings
from station.domain.record.records import PoseRecord, PoseRole, RunRecord
from station.domain.sensors.sensor import ADC_MAX
from station.domain.signals.poses import Pose, pose
from station.results.journal import JournalFile, RunJournal
from station.run import record
from station.run.acquisition import PoseResult
from station.run.capture import PoseCapture, Saturated
from station.run.gyro import LiveGyro
from station.run.messages import MessageLog
from station.run.operator_text import pose_words
from station.run.phases import REDO_ALLOWED, Phase, advance
from station.run.reconnect import Reconnect
from station.run.unit_output import UnitOutputCheck
from station.run.verdict import (
    Failures,
    Purpose,
    calibration_failed,
    conclude,
    gyro_matrix_failed,
    saturated,
    writeback_failed,
)
from station.run.view import RunView
from station.run.writeback import write_and_read_back


def open_unit(port: str, serial: str, adc_max: int = ADC_MAX) -> PutterDriver:
    """Open the unit on ``port`` (its input flushed), check it is ``serial``, start a fresh
    raw stream (of accelerometer counts up to ``adc_max``, its product's sensor's): no
    sample the unit sent before is handed out (:class:`station.device.PutterDriver`)."""
    driver = PutterDriver.open(port, adc_max=adc_max)
    try:
        driver.identify(expected_serial=serial)
        driver.start_stream()
    except BaseException:
        driver.close()
        raise
    return driver


class UnitRun:
    """The calibration of one unit, driven step by step by the interface.

    ``purpose`` says where the unit goes after its verdict (from its earlier runs), or
    that it is the station's golden unit; ``g_sensitivity`` is the scale-factor
    g-sensitivity of the unit's stored [Park2014]_ fit, taken out before its gyro matrix
    is fitted.
    """

    def __init__(
        self,
        *,
        driver: PutterDriver,
        journal: RunJournal,
        journal_file: JournalFile,
        profile: LimitsProfile,
        settings: RunSettings,
        reopen: Callable[[], PutterDriver],
        purpose: Purpose | None = None,
        g_sensitivity: FloatArray | None = None,
    ) -> None:
        self.driver = driver
        self.journal = journal
        self.journal_file = journal_file
        self.profile = profile
        self.settings = settings
        self.purpose = purpose or Purpose()
        self.sequence: tuple[Pose, ...] = tuple(pose(n) for n in journal.poses)
        self.phase = Phase.POSE
        self.index = journal.next_pose
        self.messages = MessageLog()
        self.solution: Solution | None = None
        self.record: RunRecord | None = None
        self._gyro = LiveGyro(driver.rate_hz, settings, g_sensitivity) if settings.gyro else None
        self._capture = PoseCapture(
            settings,
            journal,
            self.messages,
            settings.window_policy(profile),
            self._gyro.recorder.feed if self._gyro else None,
        )
        self._reconnect = Reconnect(self.messages, reopen)
        self._unit_output = UnitOutputCheck()
        self._failures = Failures()
        #: The live window that failed the unit before its pose was captured.
        self._evidence: PoseRecord | None = None
        self.verification_error_mg: float | None = None
        self.unit_output_error_mg: float | None = None
        #: Whether the coefficients are in the unit (written and read back).
        self.written = False

    # -- what the interface shows --------------------------------------------------

    @property
    def fit_count(self) -> int:
        """Number of poses that feed the solve."""
        return len(self.settings.poses)

    @property
    def requested(self) -> Pose | None:
        """The pose asked for now (the verification move's end once the poses are taken)."""
        if self._gyro is not None and self._gyro.verifying:
            return pose(self.settings.gyro_verification_pose)
        return self.sequence[self.index] if self.index < len(self.sequence) else None

    @property
    def verifying_gyros(self) -> bool:
        """Whether the unit is on its verification move (a whole-unit run, after its
        write-back): it waits to be turned into :attr:`requested`."""
        return self._gyro is not None and self._gyro.verifying

    def view(self) -> RunView:
        """This moment of the run, for the unit screen."""
        return RunView(
            serial=self.journal.serial,
            phase=self.phase,
            poses=self.sequence,
            index=self.index,
            taken=frozenset(self.journal.captures),
            live=self._capture.live,
            stillness=self.settings.stillness,
            messages=tuple(self.messages),
            wrong_unit=self._reconnect.wrong_unit,
        )

    # -- operator commands -----------------------------------------------------------

    @property
    def latest_pose(self) -> int | None:
        """The pose captured most recently, if any."""
        captures = self.journal.captures
        return max(captures, key=lambda i: captures[i].captured_at) if captures else None

    def redoable(self, index: int) -> bool:
        """Whether pose ``index`` can be taken again now (taken, and not too late)."""
        return index in self.journal.captures and self.phase in REDO_ALLOWED

    def redo(self, index: int) -> None:
        """Take pose ``index`` again; its current capture is kept for audit. A pose that
        cannot be (:meth:`redoable`) is said why, and nothing changes."""
        if not 0 <= index < len(self.sequence):
            return
        name = pose_words(self.sequence[index].name)
        if index not in self.journal.captures:
            refusal = tr(
                "pose {number} ({pose}) is not taken yet: nothing to redo",
                number=index + 1,
                pose=name,
            )
            self.messages.say("warn", refusal)
            return
        if self.phase not in REDO_ALLOWED:
            said = tr("too late to redo a pose: the coefficients are being written")
            self.messages.say("warn", said)
            return
        capture = self.journal.captures.pop(index)
        replaced = record.replaced_capture(capture, "redone by the operator")
        self.journal.replaced.setdefault(index, []).append(replaced)
        self.journal_file.save(self.journal)
        self.solution = None
        self.index = self.journal.next_pose
        self._restart_capture()
        said = tr("pose {number} ({pose}) will be taken again", number=index + 1, pose=name)
        self.messages.say("info", said)

    def abort(self) -> RunRecord | None:
        """Stop this unit. With poses taken, the run is recorded as failed ("aborted")."""
        if self.phase is Phase.DONE:
            return self.record
        self._failures.abort(written=self.written)
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
            self._go(Phase.RECONNECT)
            self._reconnect.lost(self.driver, exc)

    def _go(self, to: Phase) -> None:
        self.phase = advance(self.phase, to)

    def _role(self, index: int) -> PoseRole:
        return "verify" if index >= self.fit_count else "fit"

    def _restart_capture(self) -> None:
        self._capture.restart(self.driver, self.requested)

    def _step_pose(self) -> None:
        target = self.requested
        if target is None:
            return
        outcome = self._capture.poll(self.driver, self.index, target)
        if isinstance(outcome, Saturated):
            self._fail_saturated(target, outcome)
        elif outcome is not None:
            self._accept(outcome, target)

    def _fail_saturated(self, target: Pose, outcome: Saturated) -> None:
        """An axis sits at an ADC rail while the unit is still: the unit fails at once.

        The window that showed it is kept as the pose's record, as evidence.
        """
        verdict = outcome.verdict
        role = self._role(self.index)
        self._evidence = PoseRecord.of_window(
            verdict.summary, index=self.index, name=target.name, role=role
        )
        self._failures.add(saturated(verdict.saturated_axes, self.index))
        self._finish(store=True)

    def _accept(self, result: PoseResult, target: Pose) -> None:
        index = self.index
        replaced = tuple(self.journal.replaced.get(index, ()))
        capture = record.capture_of(result, index, target.name, self._role(index), replaced)
        self.journal.captures[index] = capture
        self.journal_file.save(self.journal)
        if self._gyro is not None:
            self._gyro.recorder.captured(index, result)
        said = tr("pose {number} ({pose}) captured", number=index + 1, pose=pose_words(target.name))
        self.messages.say("info", said)
        self.index = self.journal.next_pose
        if self.index >= self.fit_count and self.solution is None:
            self._solve()
        if self.phase is not Phase.POSE:
            return
        if self.index >= len(self.sequence):
            self._write_back()
        else:
            self._restart_capture()

    # -- after the poses ---------------------------------------------------------------

    def _solve(self) -> None:
        self._go(Phase.SOLVE)
        try:
            means = record.fit_means(self.journal.captures, self.fit_count)
            self.solution = solve(
                means,
                self.settings.model,
                GeometryLimits(sensor=self.settings.sensor),
                max_residual_counts=self.profile.max_residual_counts,
            )
        except CalibrationError as exc:
            self._failures.add(calibration_failed(exc))
            self._finish(store=True)
            return
        self._go(Phase.POSE)
        self.messages.say("info", tr("calibration solved: now the verification pose"))

    def _write_back(self) -> None:
        self._go(Phase.WRITE_BACK)
        assert self.solution is not None
        captures = self.journal.captures
        try:
            gyro = self._gyro.coefficients(captures, self.solution) if self._gyro else None
            relative = write_and_read_back(self.driver, self.solution.calibration, gyro)
        except (GyroMatrixError, DeviceError) as exc:
            failed = gyro_matrix_failed if isinstance(exc, GyroMatrixError) else writeback_failed
            self._failures.add(failed(exc))
            self._finish(store=True)
            return
        self.written = True
        if (reason := check(self.profile, "writeback", relative)) is not None:
            self._failures.add(reason)
        self.driver.start_stream(calibrated=True)
        self._unit_output = UnitOutputCheck(keep_streaming=self._gyro is not None)
        self._go(Phase.UNIT_OUTPUT)
        self.messages.say(
            "info", tr("coefficients written and read back: checking the unit's own output")
        )

    def _step_unit_output(self) -> None:
        gyro = self._gyro
        if gyro is not None and gyro.verifying:
            if gyro.poll_verification(self.driver):
                self._finish(store=True)
            return
        error_mg = self._unit_output.poll(self.driver)
        if error_mg is None:
            return
        self.unit_output_error_mg = error_mg
        if (reason := check(self.profile, "unit_output", error_mg)) is not None:
            self._failures.add(reason)
        if gyro is None:
            self._finish(store=True)
        else:
            self.messages.say("info", gyro.start_verification(self._unit_output))

    def _step_reconnect(self) -> None:
        driver = self._reconnect.attempt()
        if driver is None:
            return
        self.driver = driver
        self._capture.forget_window()
        if self.index >= len(self.sequence):  # it went while its coefficients were written
            self._write_back()
        else:
            self._go(Phase.POSE)
            self._restart_capture()

    # -- the verdict -------------------------------------------------------------------

    def _finish(self, *, store: bool) -> None:
        self._go(Phase.VERDICT)
        gyro = self._gyro
        outcome = conclude(
            self.journal,
            self.settings,
            self.profile,
            self.solution,
            self._failures,
            purpose=self.purpose,
            evidence=self._evidence,
            gyro_checks=gyro.checks(self.profile) if gyro is not None else (),
            gyro_matrix=gyro.record() if gyro is not None else None,
            gyro_fit=gyro.fit if gyro is not None else None,
            store=store,
        )
        self.verification_error_mg = outcome.verification_error_mg
        self.record = outcome.record
        self._go(Phase.DONE)
        self._capture.clear_view()
