"""A unit's way through the station, once for every front-end: scanned, opened in its
slot, calibrated, judged, stored.

The one-port station (:class:`station.loop.app.StationApp`) is a station of one slot;
the fixture (:class:`station.loop.fixture.app.FixtureApp`) has several. Both hand every
unit to one :class:`UnitLifecycle`, which takes it through these steps, each in one
place:

- **the scan** (:meth:`UnitLifecycle.scan`): ``quit``; the station's own checks (a
  supervisor's unlock, the lock, the golden unit due, the golden unit itself,
  :class:`station.loop.shift_checks.ShiftChecks`); a serial number; not in another
  slot; then the unit's history is looked up beside the loop
  (:meth:`station.loop.results_link.ResultsLink.look_up`), and once it is there
  (:meth:`UnitLifecycle.scanned`) it decides (:class:`station.loop.unit_history.UnitHistory`:
  passed already, ask; sent to rework or no attempts left, refuse);
- **the start** (:meth:`UnitLifecycle.start`): the unit opened on its slot's port, its
  input flushed and its stream a fresh one (:func:`station.run.unit_run.open_unit`: no
  sample sent before, such as a previous run's, is judged; the serial it reports checked
  against its label, which catches a unit in the wrong slot),
  its journal (new, or the interrupted one resumed), and its run
  (:class:`station.run.unit_run.UnitRun`) with what its record needs: its earlier runs
  or that it is the golden unit, and the stored [Park2014]_ g-sensitivity fit of a
  whole-unit run;
- **the end** (:meth:`UnitLifecycle.finish`): the record, built by the run with its
  disposition and purpose, into the outbox first, then the journal cleared, then the
  shift checks told (the golden unit judged, the drift watch fed).

The front-ends word what comes back on their own screens.
"""

import uuid
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime

from station import __version__
from station.device import DeviceError, SerialNumberMismatchError
from station.domain.calibration import Model
from station.domain.i18n import tr
from station.domain.product.limits import LimitsProfile
from station.domain.product.products import Label
from station.domain.record.records import AsFound, RunRecord
from station.loop.config import StationConfig
from station.loop.results_link import ResultsLink, UnitLookup
from station.loop.shift_checks import ShiftChecks
from station.loop.slot import Slot, SlotState
from station.loop.unit_history import ScanAction, ScanDecision, UnitHistory
from station.results.journal import DiscardedJournal, RunJournal
from station.results.storage import RunStore
from station.run.operator_text import (
    disposition_word,
    not_a_label,
    not_a_serial,
    other_product,
    port_problem,
    said_of,
    serial_mismatch,
    verdict_word,
)
from station.run.record import ALGORITHMS
from station.run.unit_run import UnitRun, open_unit
from station.run.verdict import Purpose
from station.run.writeback import read_as_found


@dataclass(frozen=True)
class Quit:
    """``quit`` was typed at the scan."""


@dataclass(frozen=True)
class Said:
    """The station's own answer to a scanned line: nothing is calibrated."""

    text: str


@dataclass(frozen=True)
class Looking:
    """A unit whose history is asked of the results store, beside the loop."""

    serial: str
    golden: bool = False


@dataclass(frozen=True)
class Scanned:
    """A unit's serial number scanned, what the store knows of it, and what its history
    decided."""

    serial: str
    known: UnitLookup
    decision: ScanDecision

    @property
    def history(self) -> UnitHistory:
        """The unit's runs and reviews."""
        return self.known.history


@dataclass(frozen=True)
class StoredAlready:
    """An interrupted run to resume is stored already (the station quit after storing it,
    its journal's removal refused by the disk): it is not calibrated again."""

    run_id: str


@dataclass(frozen=True)
class WrongUnit:
    """The unit on the slot's port reports another serial than its label
    (``sentence``: what the operator is told)."""

    reported: str
    sentence: str


@dataclass(frozen=True)
class Unreachable:
    """The slot's port could not be opened, or the unit there does not answer."""

    problem: str


def versions(profile: LimitsProfile, model: Model) -> str:
    """Software, algorithm (the one the records of a ``model`` run name) and limits
    versions, as shown at the top of the screen."""
    p = profile
    algorithm = ALGORITHMS[model]
    return f"v{__version__} · {algorithm} · {tr('limits')} {p.name} v{p.version} ({p.sha256[:12]})"


def verdict_line(record: RunRecord) -> str:
    """``PT000042: FAIL (offset): retest``: the verdict in the station's log."""
    failed = ", ".join(f.code for f in record.failures)
    verdict = verdict_word(record.verdict) + (f" ({failed})" if failed else "")
    if record.disposition:
        verdict = said_of(verdict, disposition_word(record.disposition))
    return said_of(record.serial, verdict)


def _new_journal(
    config: StationConfig, label: Label, part_number: str, slot: int, as_found: AsFound
) -> RunJournal:
    """The journal of a new run of the unit ``label`` names (its lot, else the
    station's) on the station ``config`` describes, in its fixture's ``slot``; the unit
    held ``as_found`` when it came."""
    return RunJournal(
        run_id=uuid.uuid4(),
        serial=label.serial,
        station_id=config.station_id,
        operator_id=config.operator_id,
        lot=label.lot or config.lot,
        part_number=part_number,
        fixture_slot=slot,
        started_at=datetime.now(UTC),
        poses=(*config.run.poses, config.run.verification_pose),
        as_found=as_found,
    )


class UnitLifecycle:
    """The station's slots, its results and its own checks; every unit's steps."""

    def __init__(
        self,
        *,
        config: StationConfig,
        profile: LimitsProfile,
        slots: Sequence[Slot],
        open_store: Callable[[], RunStore],
        say_line: Callable[[str], None],
    ) -> None:
        self.config = config
        self.profile = profile
        self.slots = slots
        self.results = ResultsLink(
            outbox_dir=config.outbox_dir,
            data_dir=config.data_dir.expanduser(),
            journal_files=[slot.journal_file for slot in slots],
            open_store=open_store,
            say_line=say_line,
        )
        #: The golden unit, the lock and the drift warning (docs/station.md).
        self.checks = ShiftChecks(config.golden, config.data_dir.expanduser(), config.station_id)
        #: Every run recorded since the station started, in order.
        self.records: list[RunRecord] = []
        #: The product the station calibrates.
        self.product = config.product
        #: The label of each unit scanned and not yet started, by serial.
        self._labels: dict[str, Label] = {}

    @property
    def versions(self) -> str:
        """Software, algorithm and limits versions, as shown at the top."""
        return versions(self.profile, self.config.run.model)

    def open_results(self) -> None:
        """Reach the store and send what waits in the outbox, beside the loop."""
        self.results.open()

    def interrupted(
        self,
    ) -> tuple[list[tuple[Slot, RunJournal]], list[tuple[Slot, DiscardedJournal]]]:
        """Each slot's run left by a crash, and each journal that could not be resumed."""
        found: list[tuple[Slot, RunJournal]] = []
        discarded: list[tuple[Slot, DiscardedJournal]] = []
        for slot in self.slots:
            loaded = slot.journal_file.load()
            if isinstance(loaded, DiscardedJournal):
                discarded.append((slot, loaded))
            elif loaded is not None:
                found.append((slot, loaded))
        return found, discarded

    def scan(self, text: str, slot: Slot) -> Quit | Said | Looking:
        """What a line scanned (or typed) for ``slot`` asks for; a unit's history is
        then looked up (:meth:`scanned` gives the decision once it is there)."""
        if text.lower() == "quit":
            return Quit()
        gate = self.checks.at_scan(text)
        if gate.said is not None:
            return Said(gate.said)
        if gate.golden:  # calibrated at every check: no re-scan question, no retest limit
            return self.look_up(text, golden=True)
        label = self.read_label(text)
        if isinstance(label, Said):
            return label
        text = label.serial
        elsewhere = next((s for s in self.slots if s.serial == text and s is not slot), None)
        if elsewhere is not None:
            return Said(
                tr(
                    "{serial} is in {other} already: scan the unit in {slot} "
                    "(Enter: leave {slot} empty)",
                    serial=text,
                    other=elsewhere.name,
                    slot=slot.name,
                )
            )
        self._labels[text] = label
        return self.look_up(text)

    def read_label(self, text: str) -> Label | Said:
        """The label scanned (the station's label pattern, else a bare serial number),
        or why it is refused: not a label, or another product's."""
        form = self.config.label
        if form is None:
            refused = not_a_serial(text, self.config.serial_pattern)
            return Said(refused) if refused is not None else Label(serial=text)
        label = form.read(text)
        if label is None:
            return Said(not_a_label(text, form.pattern))
        refused = not_a_serial(label.serial, self.config.serial_pattern)
        if refused is not None:
            return Said(refused)
        ours = self.product.part_number
        if label.part_number is not None and label.part_number != ours:
            return Said(other_product(label.serial, label.part_number, ours))
        return label

    def label_refused(self, text: str) -> str | None:
        """Why a label scanned ahead, during a unit or a cycle, is refused (None: it is
        read): the check of every scan (:meth:`read_label`), for every front-end."""
        label = self.read_label(text)
        return label.text if isinstance(label, Said) else None

    def look_up(self, serial: str, *, golden: bool = False) -> Looking:
        """Ask the store about ``serial`` beside the loop (its stored fit too, when the
        runs fit the gyro matrix)."""
        self.results.look_up(serial, gyro=self.config.run.gyro)
        return Looking(serial, golden)

    def scanned(self, looking: Looking) -> Scanned | None:
        """The decision about a unit looked up, once the store's answer is there."""
        known = self.results.looked_up(looking.serial)
        if known is None:
            return None
        if looking.golden:
            return Scanned(looking.serial, known, ScanDecision(ScanAction.START))
        decision = known.history.at_scan(self.profile.attempts_allowed, self.product.part_number)
        return Scanned(looking.serial, known, decision)

    def start(
        self, slot: Slot, known: UnitLookup, journal: RunJournal | None = None
    ) -> UnitRun | WrongUnit | Unreachable | StoredAlready:
        """Open the unit ``known`` is about in ``slot`` and start its run (``journal``:
        resume it, unless its run is stored already)."""
        history = known.history
        serial, port = history.serial, slot.port
        if journal is not None and any(r.run_id == journal.run_id for r in history.runs):
            slot.journal_file.clear()
            return StoredAlready(str(journal.run_id))
        if port is None:
            return Unreachable(tr("no putter port configured (--port)"))
        try:
            driver = open_unit(port, serial, self.product.sensor.adc_max)
        except SerialNumberMismatchError as exc:
            return WrongUnit(exc.reported, serial_mismatch(exc.expected, exc.reported))
        except DeviceError as exc:
            return Unreachable(port_problem(exc))
        if journal is None:
            try:
                as_found = read_as_found(driver, gyro=self.config.run.gyro)
            except DeviceError as exc:
                driver.close()
                return Unreachable(port_problem(exc))
            label = self._labels.pop(serial, None) or Label(serial=serial)
            journal = _new_journal(
                self.config, label, self.product.part_number, slot.number, as_found
            )
            # A disk that refuses does not stop the unit: the journal owes the write and
            # DiskWatch says so until it goes through (docs/station.md, fault matrix).
            slot.journal_file.save(journal)
        golden = self.checks.golden.is_golden(serial)
        settings = self.config.run
        run = UnitRun(
            driver=driver,
            journal=journal,
            journal_file=slot.journal_file,
            profile=self.profile,
            settings=settings,
            reopen=lambda: open_unit(port, serial, self.product.sensor.adc_max),
            purpose=Purpose(earlier=history.counted, golden=golden),
            g_sensitivity=known.g_sensitivity,
        )
        slot.begin(serial, run)
        return run

    def finish(self, slot: Slot) -> tuple[RunRecord | None, str | None]:
        """The slot's run ended: its record kept (None: nothing to store) and the shift
        checks' line about it (None: nothing to say)."""
        run = slot.run
        assert run is not None
        run.driver.close()
        record = run.record
        if record is not None:
            self.results.put(record)  # kept before its journal goes
        slot.journal_file.clear()
        slot.end(record)
        if record is None:
            return None, None
        self.records.append(record)
        return record, self.checks.at_verdict(record)

    @property
    def running(self) -> list[Slot]:
        """The slots whose unit is being calibrated."""
        return [s for s in self.slots if s.state is SlotState.RUNNING]

    def enough(self, units: int | None) -> bool:
        """Whether ``units`` runs are recorded (None: never enough)."""
        return units is not None and len(self.records) >= units

    def close(self) -> None:
        """Close every unit's link still open and the store's connection."""
        for slot in self.running:
            assert slot.run is not None
            slot.run.driver.close()
        self.results.close()
