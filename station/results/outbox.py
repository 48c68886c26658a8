"""The station's outbox: every finished run goes here first, then to the store.

A run is written to the outbox (one JSON file per run UUID, atomically) before any
attempt to store it, and removed only once the store confirmed it. The stores are
idempotent on the run UUID, so a record sent twice (a crash between the store's
answer and the removal) is still stored once. Nothing in the outbox stops it:

- the store unreachable, or refusing this station's key or URL: the pass stops and
  every record waits (the operator sees why);
- the store failing on one record (a 500, a database error on its rows): that record
  is retried with backoff (:mod:`station.results.backoff`) and the ones behind it go on;
- the store saying the record itself is invalid (400, 409, 413, 422): it moves to
  ``refused/`` with the reason;
- a record of another station (the station was renamed with runs still queued): the
  store refuses it unsent (:class:`station.results.storage.HttpStore`), and it moves to
  ``refused/`` saying whose key stores it;
- a file that is not a readable run record: it moves to ``unreadable/`` with the
  reason (:mod:`station.results.outbox_files`);
- the disk refusing the record's file (full, read-only): the record is kept in memory,
  written again at every sync and sent from memory meanwhile.

Each record goes with the outbox's report
(:class:`station.domain.record.outbox_report.OutboxReport`):
the runs still waiting behind it, the oldest one's wait, and the files set aside, so that
the results server sees a backlog building at a station (its ``[[outbox]]`` alert rule).
"""

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path

from station.domain.i18n import tr, trn
from station.domain.record.outbox_report import OutboxReport
from station.domain.record.records import RunRecord
from station.results.backoff import RecordBackoff
from station.results.files import write_atomic
from station.results.outbox_files import UnreadableRecordError, read_record, set_aside
from station.results.storage import (
    RecordFailedError,
    RunStore,
    StoreUnavailableError,
    SubmissionRefusedError,
)

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class SyncResult:
    """What one sync did, what still waits, and why it stopped early (``error``)."""

    stored: int
    refused: int
    pending: int
    error: str | None = None
    #: Files set aside as unreadable in this pass.
    unreadable: int = 0
    #: Waiting records the store failed on, retried with backoff, and one such reason.
    failing: int = 0
    failure: str | None = None

    def note(self) -> str | None:
        """One plain line for the operator about this sync (None when all went well), in
        the operator's language; the store's own words (``error``, ``failure``) as said."""
        lines = []
        if self.error is not None:
            lines.append(f"{waiting(self.pending)}: {self.error}")
        if self.failing:
            lines.append(
                tr(
                    "the store keeps failing on {runs} ({failure}): retried with backoff, "
                    "the others are sent",
                    runs=_runs(self.failing),
                    failure=self.failure,
                )
            )
        aside = [tr("{count} refused", count=self.refused)] if self.refused else []
        aside += [tr("{count} unreadable", count=self.unreadable)] if self.unreadable else []
        if aside:
            lines.append(
                tr("{what} set aside: see calstation outbox list", what=tr(" and ").join(aside))
            )
        return " · ".join(lines) or None


class Outbox:
    """A directory of run records waiting to be stored."""

    def __init__(self, directory: Path, *, backoff: RecordBackoff | None = None) -> None:
        self.directory = directory
        self.refused_dir = directory / "refused"
        self.unreadable_dir = directory / "unreadable"
        self.backoff = backoff or RecordBackoff()
        #: Records the disk refused to hold, oldest first, kept until written or stored.
        self.unwritten: list[RunRecord] = []
        #: Why the latest write failed (None once a write succeeded).
        self.write_error: OSError | None = None
        #: The station's loop puts runs while a worker thread sends them: the records
        #: kept in memory change under this lock only (never held across a network call).
        self._lock = threading.Lock()
        directory.mkdir(parents=True, exist_ok=True)

    def put(self, record: RunRecord) -> None:
        """Keep ``record`` until it is stored: on disk, or in memory if the disk refuses."""
        with self._lock:
            self.unwritten.append(record)
        self.flush()

    def flush(self) -> None:
        """Write the records kept in memory, oldest first, until the disk refuses one."""
        with self._lock:
            while self.unwritten:
                record = self.unwritten[0]
                try:
                    write_atomic(self._path(record), record.model_dump_json())
                except OSError as exc:
                    if self.write_error is None:
                        log.error("cannot write run %s to the outbox: %s", record.run_id, exc)
                    self.write_error = exc
                    return
                self.unwritten.pop(0)
            self.write_error = None

    def _forget(self, record: RunRecord) -> None:
        """The store holds ``record``: no longer kept in memory (written meanwhile, its
        file goes at the next pass: sending it again stores nothing new)."""
        with self._lock:
            if record in self.unwritten:
                self.unwritten.remove(record)

    def pending(self) -> list[Path]:
        """The waiting records' files, oldest first."""
        return sorted(self.directory.glob("*.json"), key=_age)

    def count(self) -> int:
        """How many runs wait to be stored (on disk and in memory)."""
        return len(self.pending()) + len(self.unwritten)

    def oldest_age_s(self, now: float) -> float:
        """Seconds the oldest waiting run has waited at ``now`` (``time.time()``; 0 when
        none waits): its file's age, or its finish for a run the disk refused."""
        written = [mtime_ns / 1e9 for mtime_ns, _ in map(_age, self.pending()) if mtime_ns]
        kept = [record.finished_at.timestamp() for record in list(self.unwritten)]
        since = min(written + kept, default=now)
        return max(0.0, now - since)

    def set_aside(self) -> tuple[int, int]:
        """How many files were set aside: (unreadable, refused)."""
        return _count(self.unreadable_dir), _count(self.refused_dir)

    def sync(self, store: RunStore) -> SyncResult:
        """Send every waiting record that is due, oldest first.

        Stops at the first sign the store is unreachable or refuses this station.
        """
        self.flush()
        tally = _Tally(backlog=self._backlog())
        try:
            with self._lock:
                in_memory = list(self.unwritten)
            for record in in_memory:
                self._send(store, record, tally, partial(self._forget, record))
            if not self.unwritten:
                self.write_error = None  # whatever the disk refused is stored now
            for path in self.pending():
                self._send_file(store, path, tally)
        except StoreUnavailableError as exc:
            return tally.result(self, str(exc))
        return tally.result(self, None)

    def _backlog(self) -> "_Backlog":
        """What waits now: each record's name and when it was queued (its file's time, or
        its finish for one kept in memory), oldest first; the files set aside."""
        ages = ((path.name, _age(path)[0]) for path in self.pending())
        written = {name: mtime_ns / 1e9 for name, mtime_ns in ages if mtime_ns}
        with self._lock:
            kept = {_name(r): r.finished_at.timestamp() for r in self.unwritten}
        queued = dict(sorted({**written, **kept}.items(), key=lambda item: item[1]))
        return _Backlog(queued, sum(self.set_aside()))

    def _send_file(self, store: RunStore, path: Path, tally: "_Tally") -> None:
        if not self.backoff.due(path.name):
            return
        try:
            record = read_record(path)
        except UnreadableRecordError as exc:
            log.warning("outbox file %s is unreadable: %s", path.name, exc)
            if set_aside(path, self.unreadable_dir, str(exc)):
                tally.unreadable += 1
                tally.backlog.gone(path.name)
                self.backoff.forget(path.name)
            else:
                self.backoff.failed(
                    path.name, tr("unreadable and cannot be moved aside: {error}", error=exc)
                )
            return
        self._send(store, record, tally, lambda: _remove(path), path)

    def _send(
        self,
        store: RunStore,
        record: RunRecord,
        tally: "_Tally",
        done: Callable[[], None],
        path: Path | None = None,
    ) -> None:
        """Submit one record; ``done`` forgets it once stored."""
        name = _name(record)
        if not self.backoff.due(name):
            return
        try:
            store.submit(record, tally.report(name, time.time()))
        except RecordFailedError as exc:
            wait = self.backoff.failed(name, str(exc))
            log.warning("%s; next try in %.0f s, the other runs go on", exc, wait)
            return
        except SubmissionRefusedError as exc:
            log.warning("run %s refused by the store: %s", record.run_id, exc)
            if path is None:
                path = self._path(record)
                try:
                    write_atomic(path, record.model_dump_json())
                except OSError:
                    self.backoff.failed(name, str(exc))
                    return
                done()
            if set_aside(path, self.refused_dir, str(exc)):
                tally.refused += 1
                tally.backlog.gone(name)
                self.backoff.forget(name)
            else:
                self.backoff.failed(name, str(exc))
            return
        done()
        self.backoff.forget(name)
        tally.backlog.gone(name)
        tally.stored += 1

    def _path(self, record: RunRecord) -> Path:
        return self.directory / _name(record)


@dataclass
class _Backlog:
    """The records waiting at a pass's start, by name, when each was queued (``time.time()``),
    oldest first, less those stored or set aside since; the files set aside before it."""

    queued: dict[str, float]
    set_aside: int

    def gone(self, name: str) -> None:
        """The record ``name`` no longer waits (stored, or set aside)."""
        self.queued.pop(name, None)

    def behind(self, name: str, now: float) -> tuple[int, int]:
        """The records waiting besides ``name``: how many, and the oldest one's whole
        seconds of wait at ``now`` (0: none)."""
        others = len(self.queued) - (name in self.queued)
        oldest = next((since for other, since in self.queued.items() if other != name), now)
        return others, max(0, int(now - oldest))


@dataclass
class _Tally:
    backlog: _Backlog
    stored: int = 0
    refused: int = 0
    unreadable: int = 0

    def report(self, name: str, now: float) -> OutboxReport:
        """The outbox's report sent with the record ``name`` at ``now``."""
        queued, oldest_s = self.backlog.behind(name, now)
        aside = self.backlog.set_aside + self.refused + self.unreadable
        return OutboxReport(queued=queued, oldest_s=oldest_s, set_aside=aside)

    def result(self, outbox: Outbox, error: str | None) -> SyncResult:
        waiting = {p.name for p in outbox.pending()} | {_name(r) for r in outbox.unwritten}
        failures = outbox.backoff.reasons(waiting)
        return SyncResult(
            stored=self.stored,
            refused=self.refused,
            pending=len(waiting),
            error=error,
            unreadable=self.unreadable,
            failing=len(failures),
            failure=next(reversed(failures.values()), None),
        )


def _runs(n: int) -> str:
    return trn("{count} run", "{count} runs", n)


def waiting(n: int) -> str:
    """ "1 run waits in the outbox", "3 runs wait in the outbox": a note's first words, in
    the operator's language."""
    return trn("{count} run waits in the outbox", "{count} runs wait in the outbox", n)


def _name(record: RunRecord) -> str:
    return f"{record.run_id}.json"


def _age(path: Path) -> tuple[int, str]:
    try:
        return path.stat().st_mtime_ns, path.name
    except OSError:
        return 0, path.name


def _count(directory: Path) -> int:
    try:
        return sum(1 for _ in directory.glob("*.json"))
    except OSError:
        return 0


def _remove(path: Path) -> None:
    """Forget a stored record's file; if the disk refuses, it is sent again (idempotent)."""
    try:
        path.unlink(missing_ok=True)
    except OSError as exc:
        log.error("run stored but %s cannot be removed (%s): it will be sent again", path, exc)
