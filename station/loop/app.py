"""The one-port station: serial prompt, one unit after another, verdict banners.

:class:`StationApp` is a station of one slot: it reads the operator's keys (a terminal,
or the demo's scripted operator) and acts on what they answer (:mod:`station.loop.prompt`),
hands each unit to the unit lifecycle (:class:`station.loop.lifecycle.UnitLifecycle`:
scan, start, finish), steps the unit in progress, and draws the screens
(:mod:`station.loop.screens`). A journal left by a crash is offered for resumption at
start, and the next unit's label scanned during a unit is kept on disk until taken.
"""

import logging
from collections.abc import Callable

from rich.console import Console, Group, RenderableType

from station.device import DeviceError, PutterDriver
from station.domain.i18n import tr
from station.domain.product.limits import LimitsProfile
from station.domain.record.records import RunRecord
from station.loop.config import StationConfig
from station.loop.keyboard import KeySource
from station.loop.lifecycle import (
    Looking,
    Quit,
    Said,
    Scanned,
    StoredAlready,
    Unreachable,
    WrongUnit,
    verdict_line,
)
from station.loop.live_loop import TICK_S, FrontEnd
from station.loop.prompt import (
    UNIT_KEYS,
    Label,
    LabelReader,
    Prompt,
    Recalibrate,
    Resume,
    Serial,
    State,
)
from station.loop.results_link import UnitLookup
from station.loop.slot import Slot
from station.loop.unit_history import ScanAction
from station.results.journal import JournalFile, QueuedLabelFile, RunJournal
from station.results.storage import RunStore
from station.run.operator_text import port_problem, said_of
from station.run.phases import Phase
from station.run.unit_run import UnitRun

log = logging.getLogger(__name__)


class StationApp(FrontEnd):
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
        tick_s: float = TICK_S,
        probe_ports: bool = True,
    ) -> None:
        self.slot = Slot(1, config.port, JournalFile(config.journal_path))
        #: The next unit's label, scanned during a unit, as kept on disk.
        self.queued_file = QueuedLabelFile(config.queued_label_path)
        self._kept_label: str | None = None
        super().__init__(
            config=config,
            profile=profile,
            slots=[self.slot],
            open_store=open_store,
            keys=keys,
            console=console,
            units=units,
            tick_s=tick_s,
            probe_ports=probe_ports,
        )
        self.prompt = Prompt()
        #: During a unit: tells the next unit's label from the unit's keys.
        self.labels = LabelReader(UNIT_KEYS)
        #: What the store knows of the scanned unit (its history, asked about in CONFIRM).
        self.known: UnitLookup | None = None
        #: The unit whose history is being looked up, the journal to resume then, and
        #: the keys typed meanwhile.
        self.looking: Looking | None = None
        self._resume: RunJournal | None = None
        self._held = ""
        self.last_record: RunRecord | None = None

    @property
    def run(self) -> UnitRun | None:
        """The unit in progress."""
        return self.slot.run

    # -- start and loop ------------------------------------------------------------------

    def _port_lines(self) -> list[str]:
        port = self.config.port
        if not self.probe_ports:
            return []
        if port is None:
            return [tr("no putter port configured")]
        try:
            PutterDriver.open(port).close()
        except DeviceError as exc:
            return [
                tr(
                    "putter port {port}: {problem} (waiting for a unit)",
                    port=port,
                    problem=port_problem(exc),
                )
            ]
        return []

    def _begin(self) -> None:
        self.prompt.next_serial = self._kept_label = self.queued_file.load()
        interrupted, discarded = self.lifecycle.interrupted()
        for _, unreadable in discarded:
            self._tell(unreadable.sentence)
        for _, journal in interrupted:
            self.prompt.ask_resume(journal)
            self._say_line(
                tr(
                    "unit {serial} was interrupted at pose {number} of {total}: resume it? (y/n)",
                    serial=journal.serial,
                    number=journal.next_pose + 1,
                    total=len(journal.poses),
                )
            )

    def tick(self) -> None:
        """One pass: keys, the unit in progress, the outbox."""
        try:
            typed = self.keys.read()
        except EOFError:
            typed = ""
            self._stop()
        self._keys(typed)
        self._keep_label()
        self.results.poll()
        self._stopping_tick()
        self._take_lookup()
        run = self.run
        if run is not None:
            run.step()
            for message in self.slot.unsaid():
                self._say_line(said_of(run.journal.serial, message.text))
            if run.phase is Phase.DONE:
                self._finish_unit()
        if self.prompt.state is not State.UNIT:
            self.results.sync_if_due()

    def screen(self) -> RenderableType:
        """The whole screen as it stands."""
        run = self.run.view() if self.run is not None else None
        return Group(*self.top(), self.prompt.screen(run, self.last_record, self.labels.typed))

    # -- keys ----------------------------------------------------------------------------

    def _keys(self, typed: str) -> None:
        """Act on everything typed since the last tick: during a unit, a scanned label is
        the next unit's, never keys (:class:`station.loop.prompt.LabelReader`). While a
        unit is looked up, keys are kept until its answer is in."""
        for i, key in enumerate(typed):
            if self.looking is not None:
                self._held += typed[i:]
                return
            if self.prompt.state is State.UNIT and not self.prompt.asking:
                self._unit_keys(typed[i:])
                return
            self._key(key)

    def _unit_keys(self, typed: str) -> None:
        for event in self.labels.feed(typed):
            if isinstance(event, Label):
                self._label(event.text)
            else:
                self._key(event)

    def _label(self, text: str) -> None:
        """A label scanned during the unit: the next unit's (not the unit on the station),
        checked at once as every scan is (:meth:`UnitLifecycle.label_refused`); a label
        refused never replaces the one queued."""
        run = self.run
        assert run is not None
        refused = self.lifecycle.label_refused(text)
        if refused is not None:
            run.messages.say("warn", refused)
            return
        if text == self.slot.serial:
            run.messages.say(
                "warn", tr("{serial} is the unit on the station now: finish it first", serial=text)
            )
            return
        self.prompt.next_serial = text
        run.messages.say(
            "info", tr("next unit {serial} scanned: Enter at the prompt takes it", serial=text)
        )

    def _keep_label(self) -> None:
        """Keep the next unit's label on disk whenever it changes (queued or taken)."""
        if self.prompt.next_serial != self._kept_label:
            self._kept_label = self.prompt.next_serial
            self.queued_file.save(self._kept_label)

    def _key(self, key: str) -> None:
        answer = self.prompt.key(key, self.run)
        if isinstance(answer, Serial):
            self._submit_serial(answer.text)
        elif isinstance(answer, Resume) and answer.yes:
            self._look_up(self.lifecycle.look_up(answer.journal.serial), answer.journal)
        elif isinstance(answer, Resume):
            self.slot.journal_file.clear()
            self._tell(tr("interrupted run of {serial} discarded", serial=answer.journal.serial))
        elif isinstance(answer, Recalibrate) and answer.yes and self.known is not None:
            self._start_unit(self.known)
        elif isinstance(answer, Recalibrate):
            self.prompt.note = tr("not calibrated again: scan the next unit")

    @property
    def last_note(self) -> str | None:
        """The note shown last (what the station last told the operator)."""
        return self.prompt.note

    def _tell(self, note: str) -> None:
        """Show ``note`` under the prompt, and log it."""
        self.prompt.note = note
        self._say_line(note)

    # -- units ---------------------------------------------------------------------------

    def _submit_serial(self, text: str) -> None:
        scan = self.lifecycle.scan(text, self.slot)
        if isinstance(scan, Quit):
            self._stop()
        elif isinstance(scan, Said):
            self._tell(scan.text)
        else:
            self._look_up(scan)

    def _look_up(self, looking: Looking, resume: RunJournal | None = None) -> None:
        """Wait, beside the loop, for what the store knows of the unit (then resume
        ``resume``, or decide on the scan)."""
        self.looking, self._resume = looking, resume
        self.prompt.state = State.LOOKING

    def _take_lookup(self) -> None:
        """Go on with the unit looked up once the store's answer is in."""
        looking = self.looking
        scanned = None if looking is None else self.lifecycle.scanned(looking)
        if scanned is None:
            return
        self.looking, held, self._held = None, self._held, ""
        self.prompt.state = State.SERIAL
        if self._resume is not None:
            self.known = scanned.known
            self._start_unit(scanned.known, self._resume)
        else:
            self._scanned(scanned)
        self._keys(held)

    def _scanned(self, scan: Scanned) -> None:
        self.known = scan.known
        decision = scan.decision
        if decision.note:
            self._say_line(decision.note)
        self.prompt.note = decision.text or decision.note
        if decision.text:
            self._say_line(decision.text)
        if decision.action is ScanAction.CONFIRM:
            self.prompt.state = State.CONFIRM
        elif decision.action is ScanAction.START:
            self._start_unit(scan.known, keep_note=True)

    def _start_unit(
        self, known: UnitLookup, journal: RunJournal | None = None, keep_note: bool = False
    ) -> None:
        self.last_record = None
        serial = known.history.serial
        started = self.lifecycle.start(self.slot, known, journal)
        if isinstance(started, StoredAlready):
            self._tell(
                tr(
                    "run {run_id} of {serial} is stored already: its journal was left "
                    "behind, discarded; scan the next unit",
                    run_id=started.run_id,
                    serial=serial,
                )
            )
            return
        if isinstance(started, WrongUnit):
            self._tell(started.sentence)
            return
        if isinstance(started, Unreachable):
            self._tell(
                tr(
                    "cannot reach unit {serial} on {port}: {problem}",
                    serial=serial,
                    port=self.config.port,
                    problem=started.problem,
                )
            )
            return
        self.prompt.note = self.prompt.note if keep_note else None
        self.prompt.state = State.UNIT
        self._say_line(
            tr(
                "{serial}: calibration started (run {run_id})",
                serial=serial,
                run_id=started.journal.run_id,
            )
        )

    def _finish_unit(self) -> None:
        serial = self.slot.serial
        record, said = self.lifecycle.finish(self.slot)
        self.prompt.unit_done()
        # A label half-scanned as the unit ended goes on at the serial prompt.
        self.prompt.typed, self.labels.typed = self.labels.typed, ""
        if record is None:
            self._tell(tr("unit {serial} aborted before any pose: nothing recorded", serial=serial))
        else:
            self.last_record = record
            self._say_line(verdict_line(record))
            if said:
                self._tell(said)
            self.results.sync()
        if self.lifecycle.enough(self.units):
            self.done = True
