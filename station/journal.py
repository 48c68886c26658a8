"""The run in progress, journaled after every pose so a crash loses nothing.

The station writes the whole state of the unit it is calibrating (serial, run id,
every capture taken and every capture replaced) to one JSON file after each pose,
atomically. After a crash or a power cut the station finds the file and offers to
resume the unit at the pose where it stopped; a finished or aborted run removes it.
When the disk refuses (full, read-only), the unit goes on in memory: the latest state
(or the removal) is kept and done again by :meth:`JournalFile.retry` once it can be.
"""

import logging
from datetime import datetime
from pathlib import Path
from uuid import UUID

from pydantic import BaseModel, ConfigDict, ValidationError

from station.files import write_atomic
from station.records import PoseRecord, ReplacedCapture, Vector3

log = logging.getLogger(__name__)


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
    started_at: datetime
    poses: tuple[str, ...]
    captures: dict[int, Capture] = {}
    replaced: dict[int, list[ReplacedCapture]] = {}

    @property
    def next_pose(self) -> int:
        """Index of the first pose not yet captured (``len(poses)`` when all are)."""
        return next((i for i in range(len(self.poses)) if i not in self.captures), len(self.poses))


class JournalFile:
    """The journal's file: at most one run in progress per station."""

    def __init__(self, path: Path) -> None:
        self.path = path
        #: What the disk refused: the journal to write, or True for the removal.
        self._owed: RunJournal | bool = False
        #: Why the latest write failed (None once a write succeeded).
        self.write_error: OSError | None = None

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

    def load(self) -> RunJournal | None:
        """The interrupted run, or None. An unreadable journal is kept aside, not lost."""
        try:
            text = self.path.read_text(encoding="utf-8")
        except FileNotFoundError:
            return None
        try:
            return RunJournal.model_validate_json(text)
        except ValidationError:
            self.path.replace(self.path.with_suffix(".unreadable"))
            return None

    def clear(self) -> None:
        """The run ended (stored or aborted): nothing to resume."""
        self._owed = True
        self.retry()
