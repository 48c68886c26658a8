"""The run in progress, journaled after every pose so a crash loses nothing.

The station writes the whole state of the unit it is calibrating (serial, run id,
every capture taken and every capture replaced) to one JSON file after each pose,
atomically. After a crash or a power cut the station finds the file and offers to
resume the unit at the pose where it stopped; a finished or aborted run removes it.
"""

from datetime import datetime
from pathlib import Path
from uuid import UUID

from pydantic import BaseModel, ConfigDict, ValidationError

from station.files import write_atomic
from station.records import PoseRecord, ReplacedCapture, Vector3


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

    def save(self, journal: RunJournal) -> None:
        """Write the state durably (atomic replace)."""
        write_atomic(self.path, journal.model_dump_json(indent=1))

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
        self.path.unlink(missing_ok=True)
