"""What the station holds only in memory when it must stop: saved anywhere it can be.

A finished run the data disk refused (:attr:`station.results.outbox.Outbox.unwritten`)
and the store could not take, or a unit's journal the disk refused
(:attr:`station.results.journal.JournalFile.unwritten`), exists nowhere but in the
station's memory. The station never stops holding the only copy: it saves each to the
first directory that takes it (a rescue directory beside the data directory, then the
machine's temporary directory), and when none does, writes the records themselves to
standard error, one JSON line each, so the terminal or the service's log keeps them.
The operator is told where they went, and how to bring them back (move the files into
the outbox, or the journal into the data directory).
"""

import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from station.domain.record.records import RunRecord
from station.results.files import disk_problem, write_atomic
from station.results.journal import RunJournal


@dataclass(frozen=True)
class Rescued:
    """Where the runs and journals held only in memory went; with no ``directory``, the
    ``lines`` to write to standard error (each one's JSON)."""

    runs: int
    journals: int
    directory: Path | None
    why_not: str | None = None
    lines: tuple[str, ...] = ()

    @property
    def sentence(self) -> str:
        """What the operator is told, in one line."""
        what = " and ".join(
            part
            for part in (
                f"{self.runs} run{'s' * (self.runs != 1)}" if self.runs else "",
                f"{self.journals} unit journal{'s' * (self.journals != 1)}"
                if self.journals
                else "",
            )
            if part
        )
        if self.directory is not None:
            return (
                f"stopped holding {what} only in memory: saved to {self.directory}; move "
                "the runs into the outbox (and a journal into the data directory) once "
                "the disk takes them"
            )
        return (
            f"stopped holding {what} only in memory, and no directory took them "
            f"({self.why_not}): they are on standard error, one JSON line each"
        )


def candidates(data_dir: Path) -> list[Path]:
    """Where the station tries to save what it holds only in memory, in order."""
    return [
        data_dir.parent / f"{data_dir.name}-rescue",
        Path(tempfile.gettempdir()) / "calstation-rescue",
    ]


def rescue(
    runs: Sequence[RunRecord], journals: Sequence[RunJournal], data_dir: Path
) -> Rescued | None:
    """Save ``runs`` and ``journals`` to the first directory that takes them all (None:
    nothing to save)."""
    if not runs and not journals:
        return None
    why_not = "no directory tried"
    for directory in candidates(data_dir):
        try:
            for run in runs:
                write_atomic(directory / f"{run.run_id}.json", run.model_dump_json())
            for journal in journals:
                name = f"journal-{journal.serial}-{journal.run_id}.json"
                write_atomic(directory / name, journal.model_dump_json(indent=1))
        except OSError as exc:
            why_not = f"{directory}: {disk_problem(exc)}"
            continue
        return Rescued(len(runs), len(journals), directory)
    lines = (*(r.model_dump_json() for r in runs), *(j.model_dump_json() for j in journals))
    return Rescued(len(runs), len(journals), None, why_not, lines)
