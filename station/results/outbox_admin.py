"""What ``calstation outbox`` does: list, show, resend and send the outbox's records.

Reads the same directory the station writes (``DATA_DIR/outbox``), and may run while
the station runs: a resend only moves a file back into the queue (atomically), and the
station's next sync sends it.
"""

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from station.domain.errors import InputError
from station.results.outbox import Outbox
from station.results.outbox_files import (
    FileSummary,
    UnreadableRecordError,
    read_record,
    reason_of,
    reason_path,
    set_aside,
    summarise,
)
from station.results.storage import RunStore, StoreError, SubmitOutcome

State = Literal["waiting", "unreadable", "refused"]

#: A run id prefix shorter than this is not looked up (too easy to hit the wrong run).
SHORTEST_PREFIX = 4


@dataclass(frozen=True)
class Entry:
    """One record file of the outbox, where it is and why."""

    state: State
    path: Path
    summary: FileSummary
    reason: str | None


def entries(outbox: Outbox) -> list[Entry]:
    """Every record file: the waiting ones (oldest first), then the unreadable, the refused.

    A waiting file that is no record (torn by a crash or a full disk, not JSON) is set
    aside with its reason first, as the station's next sync would set it aside; one the
    disk will not move is listed unreadable where it lies."""
    found: list[Entry] = []
    for path in outbox.pending():
        try:
            read_record(path)
        except UnreadableRecordError as exc:
            if not set_aside(path, outbox.unreadable_dir, str(exc)):
                found.append(Entry("unreadable", path, summarise(path), str(exc)))
            continue
        found.append(Entry("waiting", path, summarise(path), None))
    aside: tuple[tuple[State, Path], ...] = (
        ("unreadable", outbox.unreadable_dir),
        ("refused", outbox.refused_dir),
    )
    for state, directory in aside:
        found += [
            Entry(state, p, summarise(p), reason_of(p)) for p in sorted(directory.glob("*.json"))
        ]
    return found


def find(outbox: Outbox, run_id: str) -> Entry:
    """The entry whose run id (or file name) is ``run_id`` or starts with it."""
    every = entries(outbox)
    exact = [e for e in every if run_id in (e.summary.run_id, e.path.stem)]
    if exact:
        return exact[0]
    matches = [e for e in every if e.path.stem.startswith(run_id)]
    if len(run_id) < SHORTEST_PREFIX or not matches:
        raise InputError(f"no run {run_id!r} in {outbox.directory} (see calstation outbox list)")
    if len(matches) > 1:
        raise InputError(
            f"run id {run_id!r} is ambiguous: {', '.join(e.path.stem for e in matches)}"
        )
    return matches[0]


def resend(outbox: Outbox, entry: Entry) -> None:
    """Put a set-aside record back into the queue; a record that still does not read stays.

    Raises :class:`InputError` naming why it cannot go back.
    """
    if entry.state == "waiting":
        return
    try:
        read_record(entry.path)
    except UnreadableRecordError as exc:
        raise InputError(
            f"run {entry.path.stem} still unreadable ({exc}): it stays in {entry.path.parent}"
        ) from None
    target = outbox.directory / entry.path.name
    if target.exists():
        raise InputError(f"run {entry.path.stem} already waits in {outbox.directory}")
    entry.path.replace(target)
    reason_path(entry.path).unlink(missing_ok=True)


def send(entry: Entry, store: RunStore) -> SubmitOutcome:
    """Store one record now through ``store`` (another station's key, say), then forget it.

    The way out for a run a renamed station recorded under its former name: the queue
    refuses it (:meth:`Outbox._submit`), a key of that former station stores it. Raises
    :class:`InputError` naming why the record was not stored; the file then stays.
    """
    try:
        record = read_record(entry.path)
    except UnreadableRecordError as exc:
        raise InputError(f"run {entry.path.stem} is unreadable ({exc}): nothing sent") from None
    try:
        outcome = store.submit(record)
    except StoreError as exc:
        raise InputError(f"run {entry.path.stem} not stored: {exc}") from None
    entry.path.unlink()
    reason_path(entry.path).unlink(missing_ok=True)
    return outcome
