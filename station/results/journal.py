"""The run in progress, journaled after every pose so a crash loses nothing.

The station writes the whole state of the unit it is calibrating (serial, run id,
every capture taken and every capture replaced) to one JSON file after each pose,
atomically. After a crash or a power cut the station finds the file and offers to
resume the unit at the pose where it stopped; a finished or aborted run removes it.
When the disk refuses (full, read-only), the unit goes on in memory: the latest state
(or the removal) is kept and done again by :meth:`JournalFile.retry` once it can be.
A journal that cannot be resumed (cut short, not UTF-8, naming a pose this version
does not know) is renamed aside, never deleted, and the operator is told which unit's
run was discarded and why.
"""

import logging
import re
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from uuid import UUID

from pydantic import BaseModel, ConfigDict, ValidationError, field_validator

from station.domain.constants import DEFAULT_PART_NUMBER
from station.domain.errors import InputError, validation_problem
from station.domain.record.records import AsFound, PoseRecord, ReplacedCapture, Vector3
from station.domain.signals.poses import POSES
from station.results.files import disk_problem, write_atomic

log = logging.getLogger(__name__)

#: The serial number as it appears in a journal's JSON, for one too damaged to read.
_SERIAL_IN_JSON = re.compile(r'"serial"\s*:\s*"([A-Za-z0-9._:@\-]{1,64})"')


class Capture(BaseModel):
    """One accepted pose: what is stored, plus what the verdict needs beyond it."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    record: PoseRecord
    gyro_std: Vector3
    captured_at: datetime
    duration_s: float
    loss_fraction: float


class RunJournal(BaseModel):
    """Everything about the unit in progress."""

    model_config = ConfigDict(extra="forbid")

    run_id: UUID
    serial: str
    station_id: str
    operator_id: str
    lot: str | None = None
    #: The unit's product (journals from before products: the default one).
    part_number: str = DEFAULT_PART_NUMBER
    #: The fixture's slot of the run (journals from before slots were recorded: None).
    fixture_slot: int | None = None
    started_at: datetime
    poses: tuple[str, ...]
    captures: dict[int, Capture] = {}
    replaced: dict[int, list[ReplacedCapture]] = {}
    #: The coefficients the unit held when the run started (journals from before the
    #: station read them: None).
    as_found: AsFound | None = None

    @field_validator("poses")
    @classmethod
    def _known(cls, poses: tuple[str, ...]) -> tuple[str, ...]:
        unknown = [name for name in poses if name not in POSES]
        if unknown:
            raise ValueError(f"unknown pose {unknown[0]!r}")
        return poses

    @property
    def next_pose(self) -> int:
        """Index of the first pose not yet captured (``len(poses)`` when all are)."""
        return next((i for i in range(len(self.poses)) if i not in self.captures), len(self.poses))


@dataclass(frozen=True)
class DiscardedJournal:
    """A journal that could not be resumed, renamed to ``kept_as``."""

    serial: str | None
    reason: str
    kept_as: Path

    @property
    def sentence(self) -> str:
        """What the operator is told."""
        unit = f"unit {self.serial}" if self.serial else "a unit (serial unreadable)"
        return (
            f"the interrupted run of {unit} was discarded: its journal {self.reason}; "
            f"kept as {self.kept_as.name}"
        )


class JournalFile:
    """The journal's file: at most one run in progress per station."""

    def __init__(self, path: Path) -> None:
        self.path = path
        #: What the disk refused: the journal to write, or True for the removal.
        self._owed: RunJournal | bool = False
        #: Why the latest write failed (None once a write succeeded).
        self.write_error: OSError | None = None

    @property
    def unwritten(self) -> RunJournal | None:
        """The journal the disk refused to hold: kept only in memory (None: none)."""
        return self._owed if isinstance(self._owed, RunJournal) else None

    def save(self, journal: RunJournal) -> None:
        """Write the state durably (atomic replace); if the disk refuses, owe it."""
        self._owed = journal
        self.retry()

    def retry(self) -> None:
        """Do the write (or removal) the disk refused last time, if any."""
        try:
            if isinstance(self._owed, RunJournal):
                write_atomic(self.path, self._owed.model_dump_json(indent=1))
            elif self._owed:
                self.path.unlink(missing_ok=True)
        except OSError as exc:
            if self.write_error is None:
                log.error("cannot write the journal %s: %s", self.path, exc)
            self.write_error = exc
            return
        self._owed = False
        self.write_error = None

    def load(self) -> RunJournal | DiscardedJournal | None:
        """The interrupted run; None when there is none; what was set aside when unreadable.

        Raises :class:`InputError` when the file is there but cannot be read at all.
        """
        try:
            raw = self.path.read_bytes()
        except FileNotFoundError:
            return None
        except OSError as exc:
            raise InputError(f"{self.path}: cannot read the journal: {disk_problem(exc)}") from None
        try:
            return RunJournal.model_validate_json(raw.decode("utf-8"))
        except UnicodeDecodeError:
            reason = "is not UTF-8 text"
        except ValidationError as exc:
            if exc.errors()[0]["type"] == "json_invalid":
                reason = "is cut short or not JSON"
            else:
                reason = f"holds a bad value ({validation_problem(exc)})"
        found = _SERIAL_IN_JSON.search(raw.decode("utf-8", errors="replace"))
        stamp = datetime.now(UTC).strftime("%Y%m%dT%H%M%SZ")
        kept_as = self.path.with_name(f"{self.path.name}.{stamp}.unreadable")
        self.path.replace(kept_as)
        return DiscardedJournal(found.group(1) if found else None, reason, kept_as)

    def clear(self) -> None:
        """The run ended (stored or aborted): nothing to resume."""
        self._owed = True
        self.retry()


class QueuedLabelFile:
    """The label scanned ahead for a slot's next unit while units were calibrated (at the
    one-port station, Enter at the serial prompt takes it; at a fixture, the slot's scan
    offers it), kept on disk so that a station stopped and started again still has it."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def load(self) -> str | None:
        """The label queued (None: none, or its file unreadable)."""
        try:
            text = self.path.read_text(encoding="utf-8").strip()
        except (OSError, UnicodeDecodeError):
            return None
        return text or None

    def save(self, label: str | None) -> None:
        """Keep ``label`` as the next unit's (None: none queued), atomically; a disk that
        refuses is logged, and the label stays in the station's memory."""
        try:
            if label is None:
                self.path.unlink(missing_ok=True)
            else:
                write_atomic(self.path, f"{label}\n")
        except OSError as exc:
            log.error("cannot keep the next unit's label in %s: %s", self.path, exc)
