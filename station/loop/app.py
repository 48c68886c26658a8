"""The operator station: serial prompt, one unit after another, verdict banners.

:class:`StationApp` owns the loop: it reads the operator's keys (a terminal, or the
demo's scripted operator) and acts on what they answer (:mod:`station.loop.prompt`), steps
the unit in progress (:class:`station.run.unit_run.UnitRun`), draws the screens
(:mod:`station.loop.screens`), and hands every finished run to the outbox, which stores it
(:mod:`station.loop.results_link`). A journal left by a crash is offered for resumption at
start.
"""

import logging
import uuid
from collections.abc import Callable
from datetime import UTC, datetime

from rich.console import Console, Group, RenderableType
from rich.text import Text

from station import __version__
from station.device import DeviceError, PutterDriver, SerialNumberMismatchError
from station.domain.limits import LimitsProfile
from station.domain.records import RunRecord
from station.loop.config import StationConfig
from station.loop.keyboard import KeySource
from station.loop.live_loop import run_live
from station.loop.prompt import Prompt, Recalibrate, Resume, Serial, State
from station.loop.results_link import ResultsLink
from station.loop.screens import header
from station.loop.shift_checks import ShiftChecks
from station.loop.unit_history import ScanAction, UnitHistory
from station.results.journal import DiscardedJournal, JournalFile, RunJournal
from station.results.storage import RunStore
from station.run.operator_text import not_a_serial, port_problem
from station.run.phases import Phase
from station.run.record import ALGORITHM
from station.run.unit_run import UnitRun

log = logging.getLogger(__name__)


def open_unit(port: str, serial: str) -> PutterDriver:
    """Open the unit on ``port``, check it is ``serial``, start its raw stream."""
    driver = PutterDriver.open(port)
    try:
        driver.identify(expected_serial=serial)
        driver.start_stream()
    except BaseException:
        driver.close()
        raise
    return driver


def new_journal(config: StationConfig, serial: str) -> RunJournal:
    """The journal of a new run of ``serial`` on the station ``config`` describes."""
    return RunJournal(
        run_id=uuid.uuid4(),
        serial=serial,
        station_id=config.station_id,
        operator_id=config.operator_id,
        lot=config.lot,
        started_at=datetime.now(UTC),
        poses=(*config.run.poses, config.run.verification_pose),
    )


def versions(profile: LimitsProfile) -> str:
    """Software, algorithm and limits versions, as shown at the top of the screen."""
    p = profile
    return f"v{__version__} · {ALGORITHM} · limits {p.name} v{p.version} ({p.sha256[:12]})"


def with_disposition(
    record: RunRecord | None, history: UnitHistory | None, profile: LimitsProfile
) -> RunRecord | None:
    """The finished run with where the unit goes next, from its history."""
    if record is None or history is None:
        return record
    where = history.disposition(record, profile.attempts_allowed)
    return record.model_copy(update={"disposition": where})


def verdict_line(record: RunRecord) -> str:
    """``PT000042: FAIL (offset): retest``: the verdict in the station's log."""
    failed = ", ".join(f.code for f in record.failures)
    then = f": {record.disposition}" if record.disposition else ""
    return f"{record.serial}: {record.verdict.upper()}" + (f" ({failed})" if failed else "") + then


class StationApp:
    """One station serving units until its keys run out (or ``units`` are done)."""

    def __init__(
        self,
        *,
        config: StationConfig,
        profile: LimitsProfile,
        open_store: Callable[[], RunStore],
        keys: KeySource,
        console: Console,
        units: int | None = None,
        tick_s: float = 0.01,
        probe_port: bool = True,
    ) -> None:
        self.config = config
        self.profile = profile
        self.keys = keys
        self.console = console
        self.units = units
        self.tick_s = tick_s
        #: Try the putter port at start (the demo's port exists only while a unit is in).
        self.probe_port = probe_port
        self.journal_file = JournalFile(config.journal_path)
        self.results = ResultsLink(
            outbox_dir=config.outbox_dir,
            data_dir=config.data_dir.expanduser(),
            journal_files=[self.journal_file],
            open_store=open_store,
            say_line=self._say_line,
        )
        self.prompt = Prompt()
        #: The golden unit, the lock and the drift warning (docs/station.md).
        self.checks = ShiftChecks(config.golden, config.data_dir.expanduser(), config.station_id)
        self.run: UnitRun | None = None
        #: The scanned unit's history (asked about in CONFIRM; its verdict's disposition).
        self.history: UnitHistory | None = None
        self.last_record: RunRecord | None = None
        self.records: list[RunRecord] = []
        self.done = False
        self._said = 0

    # -- start and loop ------------------------------------------------------------------

    @property
    def versions(self) -> str:
        """Software, algorithm and limits versions, as shown at the top."""
        return versions(self.profile)

    def serve(self) -> list[RunRecord]:
        """Serve units until the keys end, ``quit`` is typed or ``units`` are done."""
        self._say_line(f"calstation {self.versions}")
        self.results.check_store()
        self.results.sync()
        if self.probe_port:
            self._check_port()
        for line in self.checks.lines():
            self._say_line(line)
        interrupted = self.journal_file.load()
        if isinstance(interrupted, DiscardedJournal):
            self._tell(interrupted.sentence)
        elif interrupted is not None:
            self.prompt.ask_resume(interrupted)
            self._say_line(
                f"unit {interrupted.serial} was interrupted at pose {interrupted.next_pose + 1} of "
                f"{len(interrupted.poses)}: resume it? (y/n)"
            )
        try:
            run_live(self.console, self.screen, self.tick, lambda: self.done, self.tick_s)
        finally:
            if self.run is not None:
                self.run.driver.close()
            self.results.close()
        return self.records

    def tick(self) -> None:
        """One pass: keys, the unit in progress, the outbox."""
        try:
            typed = self.keys.read()
        except EOFError:
            self.done = True
            return
        for key in typed:
            self._key(key)
        self.results.check_disk()
        if self.run is not None:
            self.run.step()
            self._echo_messages(self.run)
            if self.run.phase is Phase.DONE:
                self._finish_unit(self.run)
        if self.prompt.state is not State.UNIT:
            self.results.sync_if_due()

    # -- screens -------------------------------------------------------------------------

    def screen(self) -> RenderableType:
        """The whole screen as it stands."""
        results = self.results
        top = header(
            self.config.station_id,
            self.config.operator_id,
            self.versions,
            results.backlog,
            results.set_aside,
        )
        run = self.run.view() if self.run is not None else None
        checks = [Text(line, style="bold red") for line in self.checks.lines()]
        return Group(
            top, *results.status_lines(), *checks, self.prompt.screen(run, self.last_record)
        )

    def _say_line(self, text: str) -> None:
        """A line for a console that is not a terminal (logs, the demo's stderr)."""
        if not self.console.is_terminal:
            self.console.print(text, markup=False, highlight=False)

    def _echo_messages(self, run: UnitRun) -> None:
        for message in run.messages.since(self._said):
            self._say_line(f"{run.journal.serial}: {message.text}")
        self._said = run.messages.said

    # -- keys ----------------------------------------------------------------------------

    def _key(self, key: str) -> None:
        answer = self.prompt.key(key, self.run)
        if isinstance(answer, Serial):
            self._submit_serial(answer.text)
        elif isinstance(answer, Resume) and answer.yes:
            self.history = self.results.history(answer.journal.serial)
            self._start_unit(answer.journal.serial, answer.journal)
        elif isinstance(answer, Resume):
            self.journal_file.clear()
            self._tell(f"interrupted run of {answer.journal.serial} discarded")
        elif isinstance(answer, Recalibrate) and answer.yes and self.history is not None:
            self._start_unit(self.history.serial, None)
        elif isinstance(answer, Recalibrate):
            self.prompt.note = "not calibrated again: scan the next unit"

    def _tell(self, note: str) -> None:
        """Show ``note`` under the prompt, and log it."""
        self.prompt.note = note
        self._say_line(note)

    # -- units ---------------------------------------------------------------------------

    def _submit_serial(self, serial: str) -> None:
        if serial.lower() == "quit":
            self.done = True
            return
        scan = self.checks.at_scan(serial)
        if scan.said is not None:
            self._tell(scan.said)
            return
        if scan.golden:  # calibrated at every check: no re-scan question, no retest limit
            self.history = None
            self._start_unit(serial, None)
            return
        refused = not_a_serial(serial, self.config.serial_pattern)
        if refused is not None:
            self._tell(refused)
            return
        self.history = history = self.results.history(serial)
        decision = history.at_scan(self.profile.attempts_allowed)
        if decision.note:
            self._say_line(decision.note)
        self.prompt.note = decision.text or decision.note
        if decision.text:
            self._say_line(decision.text)
        if decision.action is ScanAction.CONFIRM:
            self.prompt.state = State.CONFIRM
        elif decision.action is ScanAction.START:
            self._start_unit(serial, None, keep_note=True)

    def _open_unit(self, serial: str) -> PutterDriver:
        port = self.config.port
        if port is None:
            raise DeviceError("no putter port configured (--port)")
        return open_unit(port, serial)

    def _start_unit(self, serial: str, journal: RunJournal | None, keep_note: bool = False) -> None:
        self.last_record = None
        try:
            driver = self._open_unit(serial)
        except SerialNumberMismatchError as exc:
            self._tell(f"{exc}: set the unit aside; nothing was recorded")
            return
        except DeviceError as exc:
            self._tell(f"cannot reach unit {serial} on {self.config.port}: {port_problem(exc)}")
            return
        if journal is None:
            journal = new_journal(self.config, serial)
            # A disk that refuses does not stop the unit: the journal owes the write and
            # DiskWatch says so until it goes through (docs/station.md, fault matrix).
            self.journal_file.save(journal)
        self.prompt.note = self.prompt.note if keep_note else None
        self._said = 0
        self.run = UnitRun(
            driver=driver,
            journal=journal,
            journal_file=self.journal_file,
            profile=self.profile,
            settings=self.config.run,
            reopen=lambda: self._open_unit(serial),
            g_sensitivity=self.results.g_sensitivity(serial) if self.config.run.gyro else None,
        )
        self.prompt.state = State.UNIT
        self._say_line(f"{serial}: calibration started (run {journal.run_id})")

    def _finish_unit(self, run: UnitRun) -> None:
        run.driver.close()
        record = with_disposition(run.record, self.history, self.profile)
        said = None
        if record is not None:
            record, said = self.checks.at_verdict(record)
            self.results.put(record)
        self.journal_file.clear()
        self.run = None
        self.prompt.unit_done()
        if record is None:
            self._tell(f"unit {run.journal.serial} aborted before any pose: nothing recorded")
        else:
            self.records.append(record)
            self.last_record = record
            self._say_line(verdict_line(record))
            if said:
                self._tell(said)
            self.results.sync()
        if self.units is not None and len(self.records) >= self.units:
            self.done = True

    # -- the port -----------------------------------------------------------------------

    def _check_port(self) -> None:
        if self.config.port is None:
            self._say_line("no putter port configured")
            return
        try:
            PutterDriver.open(self.config.port).close()
        except DeviceError as exc:
            self._say_line(
                f"putter port {self.config.port}: {port_problem(exc)} (waiting for a unit)"
            )
