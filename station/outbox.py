"""The station's outbox: every finished run goes here first, then to the store.

A run is written to the outbox (one JSON file per run UUID, atomically) before any
attempt to store it, and removed only once the store confirmed it. The stores are
idempotent on the run UUID, so a record sent twice (a crash between the store's
answer and the removal) is still stored once. When the store is unreachable the
records wait and the operator sees the backlog; a record the store refuses outright
moves to ``refused/`` with the reason, kept for a person to look at.
"""

import logging
from dataclasses import dataclass
from pathlib import Path

from station.files import write_atomic
from station.records import RunRecord
from station.storage import RunStore, StoreUnavailableError, SubmissionRefusedError

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SyncResult:
    """What one sync did: records stored, records refused, and why it stopped early."""

    stored: int
    refused: int
    pending: int
    error: str | None = None


class Outbox:
    """A directory of run records waiting to be stored."""

    def __init__(self, directory: Path) -> None:
        self.directory = directory
        self.refused_dir = directory / "refused"
        directory.mkdir(parents=True, exist_ok=True)

    def put(self, record: RunRecord) -> None:
        """Keep ``record`` durably until it is stored."""
        write_atomic(self.directory / f"{record.run_id}.json", record.model_dump_json())

    def pending(self) -> list[Path]:
        """The waiting records' files, oldest first."""
        return sorted(self.directory.glob("*.json"), key=lambda p: (p.stat().st_mtime_ns, p.name))

    def count(self) -> int:
        """How many runs wait to be stored."""
        return len(self.pending())

    def sync(self, store: RunStore) -> SyncResult:
        """Send every waiting record, oldest first; stop at the first unavailability."""
        stored = refused = 0
        for path in self.pending():
            record = RunRecord.model_validate_json(path.read_text(encoding="utf-8"))
            try:
                store.submit(record)
            except StoreUnavailableError as exc:
                return SyncResult(stored, refused, self.count(), str(exc))
            except SubmissionRefusedError as exc:
                self.refused_dir.mkdir(exist_ok=True)
                write_atomic(self.refused_dir / f"{path.stem}.reason.txt", f"{exc}\n")
                path.replace(self.refused_dir / path.name)
                log.warning("run %s refused by the store: %s", record.run_id, exc)
                refused += 1
                continue
            path.unlink()
            stored += 1
        return SyncResult(stored, refused, 0)
