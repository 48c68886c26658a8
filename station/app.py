"""The operator station: serial prompt, one unit after another, verdict banners.

:class:`StationApp` owns the loop: it reads the operator's keys (a terminal, or the
demo's scripted operator), steps the unit in progress (:class:`station.session.UnitRun`),
draws the screens (:mod:`station.screens`), and hands every finished run to the
outbox, which stores it (:mod:`station.outbox`). A journal left by a crash is offered
for resumption at start.
"""

import logging
import re
import time
import uuid
from collections.abc import Callable
from datetime import UTC, datetime
from enum import StrEnum

from rich.console import Console, Group, RenderableType
from rich.live import Live
from rich.text import Text
from sqlalchemy.exc import SQLAlchemyError

from station import __version__
from station.config import StationConfig
from station.device import DeviceError, PutterDriver, SerialNumberMismatchError
from station.disk import DiskWatch
from station.errors import CalstationError
from station.journal import DiscardedJournal, JournalFile, RunJournal
from station.keys import KeySource
from station.limits import LimitsProfile
from station.operator_text import port_problem
from station.outbox import Outbox, waiting
from station.records import RunRecord
from station.run.phases import Phase
from station.run.record import ALGORITHM
from station.screens import header, serial_prompt, unit_screen, verdict_screen
from station.session import UnitRun
from station.storage import RunStore
from station.unit_history import ScanAction, UnitHistory

log = logging.getLogger(__name__)

#: Seconds between attempts to empty a non-empty outbox while idle.
SYNC_EVERY_S = 5.0
#: Seconds between screen refreshes.
DRAW_EVERY_S = 0.1
ENTER = ("\r", "\n")
BACKSPACE = ("\x7f", "\b")


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


class State(StrEnum):
    """What the station waits for."""

    RESUME = "resume"
    SERIAL = "serial"
    CONFIRM = "confirm"
    UNIT = "unit"


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
    ) -> None:
        self.config = config
        self.profile = profile
        self._open_store = open_store
        self._store: RunStore | None = None
        self.keys = keys
        self.console = console
        self.units = units
        self.tick_s = tick_s
        self.outbox = Outbox(config.outbox_dir)
        self.journal_file = JournalFile(config.journal_path)
        self.state = State.SERIAL
        self.run: UnitRun | None = None
        self.pending_resume: RunJournal | None = None
        #: The scanned unit's history (asked about in CONFIRM; its verdict's disposition).
        self.history: UnitHistory | None = None
        self.typed = ""
        self.note: str | None = None
        self.last_record: RunRecord | None = None
        self.records: list[RunRecord] = []
        self.show_help = False
        self.confirm_abort = False
        self.done = False
        self._said = 0
        self._next_sync = 0.0
        self.store_note: str | None = None
        #: Runs waiting in the outbox (counted at every sync, kept up to date between).
        self.backlog = 0
        #: Outbox files set aside: (unreadable, refused), counted at every sync.
        self.set_aside = (0, 0)
        self.disk = DiskWatch(config.data_dir.expanduser(), self.journal_file, self.outbox)
        #: What the disk refused, in one line (None when every write went through).
        self.disk_note: str | None = None

    # -- start and loop ------------------------------------------------------------------

    @property
    def versions(self) -> str:
        """Software, algorithm and limits versions, as shown at the top."""
        p = self.profile
        return f"v{__version__} · {ALGORITHM} · limits {p.name} v{p.version} ({p.sha256[:12]})"

    def serve(self) -> list[RunRecord]:
        """Serve units until the keys end, ``quit`` is typed or ``units`` are done."""
        self._say_line(f"calstation {self.versions}")
        self._check_store()
        self._sync()
        self._check_port()
        interrupted = self.journal_file.load()
        if isinstance(interrupted, DiscardedJournal):
            self.note = interrupted.sentence
            self._say_line(self.note)
        elif interrupted is not None:
            self.pending_resume = interrupted
            self.state = State.RESUME
            self._say_line(
                f"unit {interrupted.serial} was interrupted at pose {interrupted.next_pose + 1} of "
                f"{len(interrupted.poses)}: resume it? (y/n)"
            )
        try:
            if self.console.is_terminal:
                with Live(self.screen(), console=self.console, auto_refresh=False) as live:
                    self._loop(lambda: live.update(self.screen(), refresh=True))
            else:
                self._loop(lambda: None)
        finally:
            if self.run is not None:
                self.run.driver.close()
            if self._store is not None:
                self._store.close()
        return self.records

    def _loop(self, draw: Callable[[], None]) -> None:
        next_draw = 0.0
        while not self.done:
            self.tick()
            now = time.monotonic()
            if now >= next_draw:
                draw()
                next_draw = now + DRAW_EVERY_S
            time.sleep(self.tick_s)
        draw()

    def tick(self) -> None:
        """One pass: keys, the unit in progress, the outbox."""
        try:
            typed = self.keys.read()
        except EOFError:
            self.done = True
            return
        for key in typed:
            self._key(key)
        self._check_disk()
        if self.run is not None:
            self.run.step()
            self._echo_messages(self.run)
            if self.run.phase is Phase.DONE:
                self._finish_unit(self.run)
        if self.state is not State.UNIT and time.monotonic() >= self._next_sync and self.backlog:
            self._sync()

    # -- screens -------------------------------------------------------------------------

    def screen(self) -> RenderableType:
        """The whole screen as it stands."""
        parts: list[RenderableType] = [
            header(
                self.config.station_id,
                self.config.operator_id,
                self.versions,
                self.backlog,
                self.set_aside,
            )
        ]
        if self.disk_note:
            parts.append(Text(self.disk_note, style="bold red"))
        if self.store_note:
            parts.append(Text(self.store_note, style="yellow"))
        if self.state is State.RESUME and self.pending_resume is not None:
            j = self.pending_resume
            parts.append(
                Text(
                    f"Unit {j.serial} was interrupted at pose {j.next_pose + 1} of {len(j.poses)}. "
                    "Resume it? press y (resume) or n (discard)",
                    style="bold yellow",
                )
            )
        elif self.state is State.CONFIRM and self.note:
            parts.append(Text(self.note, style="bold yellow"))
        elif self.state is State.UNIT and self.run is not None:
            parts.append(unit_screen(self.run.view(), self.show_help))
            if self.confirm_abort:
                parts.append(
                    Text(
                        "abort this unit? press y to confirm, any other key to go on",
                        style="bold red",
                    )
                )
        else:
            if self.last_record is not None:
                parts.append(verdict_screen(self.last_record))
            parts.append(serial_prompt(self.typed, self.note))
        return Group(*parts)

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
        if self.state is State.RESUME:
            self._resume_key(key)
        elif self.state is State.SERIAL:
            self._serial_key(key)
        elif self.state is State.CONFIRM:
            self._confirm_key(key)
        elif self.run is not None:
            self._unit_key(self.run, key)

    def _resume_key(self, key: str) -> None:
        journal = self.pending_resume
        self.pending_resume = None
        self.state = State.SERIAL
        if journal is None:
            return
        if key.lower() == "y":
            self.history = self._history(journal.serial)
            self._start_unit(journal.serial, journal)
        else:
            self.journal_file.clear()
            self.note = f"interrupted run of {journal.serial} discarded"
            self._say_line(self.note)

    def _serial_key(self, key: str) -> None:
        if key in ENTER:
            text, self.typed = self.typed.strip(), ""
            if text:
                self._submit_serial(text)
        elif key in BACKSPACE:
            self.typed = self.typed[:-1]
        elif key.isprintable():
            self.typed += key

    def _unit_key(self, run: UnitRun, key: str) -> None:
        if self.confirm_abort:
            self.confirm_abort = False
            if key.lower() == "y":
                run.abort()
            return
        if key in ("h", "?"):
            self.show_help = not self.show_help
        elif key == "r":
            run.redo_last()
        elif key.isdigit() and key != "0":
            run.redo(int(key) - 1)
        elif key == "a":
            self.confirm_abort = True

    # -- units ---------------------------------------------------------------------------

    def _submit_serial(self, serial: str) -> None:
        if serial.lower() == "quit":
            self.done = True
            return
        if not re.fullmatch(self.config.serial_pattern, serial):
            self.note = f"{serial!r} is not a serial number (expected {self.config.serial_pattern})"
            self._say_line(self.note)
            return
        self.history = history = self._history(serial)
        decision = history.at_scan(self.profile.attempts_allowed)
        if decision.note:
            self._say_line(decision.note)
        self.note = decision.text or decision.note
        if decision.text:
            self._say_line(decision.text)
        if decision.action is ScanAction.CONFIRM:
            self.state = State.CONFIRM
        elif decision.action is ScanAction.START:
            self._start_unit(serial, None, keep_note=True)

    def _confirm_key(self, key: str) -> None:
        """The answer to "passed already: calibrate again? y/n"."""
        self.state = State.SERIAL
        if self.history is not None and key.lower() == "y":
            self._start_unit(self.history.serial, None)
        else:
            self.note = "not calibrated again: scan the next unit"

    def _history(self, serial: str) -> UnitHistory:
        if self._store is None:
            self._check_store()
        return UnitHistory.gather(serial, self._store, self.outbox.pending())

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
            self.note = f"{exc}: set the unit aside; nothing was recorded"
            self._say_line(self.note)
            return
        except DeviceError as exc:
            self.note = f"cannot reach unit {serial} on {self.config.port}: {port_problem(exc)}"
            self._say_line(self.note)
            return
        if journal is None:
            run_settings = self.config.run
            journal = RunJournal(
                run_id=uuid.uuid4(),
                serial=serial,
                station_id=self.config.station_id,
                operator_id=self.config.operator_id,
                lot=self.config.lot,
                started_at=datetime.now(UTC),
                poses=(*run_settings.poses, run_settings.verification_pose),
            )
            # A disk that refuses does not stop the unit: the journal owes the write and
            # DiskWatch says so until it goes through (docs/station.md, fault matrix).
            self.journal_file.save(journal)
        self.note = self.note if keep_note else None
        self._said = 0
        self.run = UnitRun(
            driver=driver,
            journal=journal,
            journal_file=self.journal_file,
            profile=self.profile,
            settings=self.config.run,
            reopen=lambda: self._open_unit(serial),
        )
        self.state = State.UNIT
        self._say_line(f"{serial}: calibration started (run {journal.run_id})")

    def _finish_unit(self, run: UnitRun) -> None:
        run.driver.close()
        record = run.record
        if record is not None and self.history is not None:
            where = self.history.disposition(record, self.profile.attempts_allowed)
            record = record.model_copy(update={"disposition": where})
        if record is not None:
            self.outbox.put(record)
            self.backlog += 1
        self.journal_file.clear()
        self.run = None
        self.state = State.SERIAL
        self.confirm_abort = False
        self.show_help = False
        if record is None:
            self.note = f"unit {run.journal.serial} aborted before any pose: nothing recorded"
            self._say_line(self.note)
        else:
            self.records.append(record)
            self.last_record = record
            failed = ", ".join(f.code for f in record.failures)
            then = f": {record.disposition}" if record.disposition else ""
            self._say_line(
                f"{record.serial}: {record.verdict.upper()}"
                + (f" ({failed})" if failed else "")
                + then
            )
            self._sync()
        if self.units is not None and len(self.records) >= self.units:
            self.done = True

    # -- storage -------------------------------------------------------------------------

    def _sync(self) -> None:
        self._next_sync = time.monotonic() + SYNC_EVERY_S
        self.backlog = self.outbox.count()
        self.set_aside = self.outbox.set_aside()
        if not self.backlog:
            self._store_says(None)
            return
        try:
            if self._store is None:
                self._store = self._open_store()
            result = self.outbox.sync(self._store)
        except (SQLAlchemyError, OSError, CalstationError) as exc:
            self._drop_store()
            reason = str(exc) if isinstance(exc, CalstationError) else type(exc).__name__
            self._store_says(f"{waiting(self.backlog)}: results store unreachable ({reason})")
            return
        self.backlog = result.pending
        self.set_aside = self.outbox.set_aside()
        if result.error is not None:
            self._drop_store()
        self._store_says(result.note())

    def _store_says(self, note: str | None) -> None:
        """Show ``note`` about the store; a changed note also goes to the log."""
        if note is not None and note != self.store_note:
            self._say_line(note)
        self.store_note = note

    def _check_disk(self) -> None:
        note = self.disk.check()
        if note is not None and note != self.disk_note:
            self._say_line(note)
        self.disk_note = note

    def _check_store(self) -> None:
        """Connect to the store at start, so the first unit does not wait for it."""
        try:
            self._store = self._open_store()
        except (SQLAlchemyError, OSError, CalstationError) as exc:
            self.store_note = (
                f"results database unreachable ({type(exc).__name__}): runs will wait in the outbox"
            )
            self._say_line(self.store_note)
        else:
            self._say_line("results database: connected")

    def _drop_store(self) -> None:
        if self._store is not None:
            self._store.close()
            self._store = None

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
