"""The station's way to its results: the outbox, the results store, the data disk.

:class:`ResultsLink` hands every finished run to the outbox (on the loop's own thread: a
local write, done before the run's journal goes), and does everything that talks to the
results store **beside the loop**, so the operator's screen never waits on the network:

- the outbox is emptied into the store by a worker thread of its own (at start, after
  each unit, and every :data:`SYNC_EVERY_S` while runs wait), which reconnects after a
  failure;
- a unit's history, reviews and stored [Park2014]_ fit are looked up at its scan by a
  second worker (:meth:`ResultsLink.look_up`), so a slow lookup never holds up a sync
  and a hung server never freezes the screen.

The loop calls :meth:`ResultsLink.poll` every tick: what a worker finished is taken in
there, on the loop's thread, and said (one line each about the store and the disk, kept
for the screen, which also says what the station waits for).
"""

import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

from rich.console import RenderableType
from rich.text import Text

from station.domain.arrays import FloatArray
from station.domain.gyro import NotIdentifiableError
from station.domain.i18n import tr
from station.domain.record.records import RunRecord
from station.loop.unit_history import UnitHistory
from station.results.disk import DiskWatch
from station.results.journal import JournalFile
from station.results.outbox import Outbox, SyncResult, waiting
from station.results.rescue import Rescued, rescue
from station.results.storage import RunStore, StoreError
from station.run.operator_text import said_of

#: Seconds between attempts to empty a non-empty outbox while idle.
SYNC_EVERY_S = 5.0
#: Seconds a sync may run before the screen says the station waits for it.
SAY_WAITING_AFTER_S = 1.0

T = TypeVar("T")

#: Opening a store may migrate the embedded database (Alembic is not thread-safe): the
#: workers open theirs one at a time.
_OPENING = threading.Lock()


@dataclass(frozen=True)
class UnitLookup:
    """What the store (and the outbox) know of a unit at its scan: its history, and the
    scale-factor g-sensitivity ``N`` (3×3, 1/g) of its stored fit, if asked for and known,
    with a line to say when the fit could not be had."""

    history: UnitHistory
    g_sensitivity: FloatArray | None = None
    fit_note: str | None = None


class StoreWorker:
    """One thread that talks to the results store, with a connection of its own.

    Work is queued in order; the store is opened in the thread when first needed and
    dropped after a failure, so the next piece of work reconnects.
    """

    def __init__(self, open_store: Callable[[], RunStore], name: str) -> None:
        self._open_store = open_store
        self._store: RunStore | None = None
        #: Why the store could not be opened last time (None: it was, or not tried).
        self.unavailable: str | None = None
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix=name)

    def submit(self, work: Callable[[RunStore | None], T]) -> "Future[T]":
        """Run ``work`` with the store (None: it cannot be opened now) in the thread."""
        return self._pool.submit(self._run, work)

    def _run(self, work: Callable[[RunStore | None], T]) -> T:
        if self._store is None:
            try:
                with _OPENING:
                    self._store = self._open_store()
                self.unavailable = None
            except StoreError as exc:
                self._store, self.unavailable = None, str(exc)
        try:
            return work(self._store)
        except BaseException:
            self.drop()
            raise

    def drop(self) -> None:
        """Close the store's connection; the next work opens a new one."""
        if self._store is not None:
            self._store.close()
            self._store = None

    def close(self, wait: bool) -> None:
        """Stop taking work; ``wait``: finish what is under way (and its connection)."""
        self._pool.shutdown(wait=wait, cancel_futures=True)
        if wait:
            self.drop()


@dataclass(frozen=True)
class _Synced:
    """What a sync did, or why it could not start (``error``)."""

    result: SyncResult | None = None
    error: str | None = None


class ResultsLink:
    """The outbox, the store behind it and the disk under both, with their status lines."""

    def __init__(
        self,
        *,
        outbox_dir: Path,
        data_dir: Path,
        journal_files: Sequence[JournalFile],
        open_store: Callable[[], RunStore],
        say_line: Callable[[str], None],
    ) -> None:
        self.outbox = Outbox(outbox_dir)
        self._say_line = say_line
        self._sender = StoreWorker(open_store, "results-sync")
        self._reader = StoreWorker(open_store, "results-lookup")
        self._opened: Future[bool] | None = None
        self._sync: Future[_Synced] | None = None
        self._sync_started = 0.0
        self._next_sync = 0.0
        self._lookups: dict[str, Future[UnitLookup]] = {}
        self.store_note: str | None = None
        #: Runs waiting in the outbox (counted at every sync, kept up to date between).
        self.backlog = 0
        #: Outbox files set aside: (unreadable, refused), counted at every sync.
        self.set_aside = (0, 0)
        self.disk = DiskWatch(data_dir, journal_files, self.outbox)
        #: What the disk refused, in one line (None when every write went through).
        self.disk_note: str | None = None

    # -- what the screen shows -----------------------------------------------------------

    def status_lines(self) -> list[RenderableType]:
        """What the disk refuses, how the store fares and what the station waits for."""
        lines: list[RenderableType] = []
        if self.disk_note:
            lines.append(Text(self.disk_note, style="bold red"))
        if self.store_note:
            lines.append(Text(self.store_note, style="yellow"))
        for serial in self._lookups:
            lines.append(
                Text(tr("waiting for the results store: the history of {serial}…", serial=serial))
            )
        if self._sync is not None and time.monotonic() - self._sync_started > SAY_WAITING_AFTER_S:
            lines.append(
                Text(tr("waiting for the results store: {waiting}…", waiting=waiting(self.backlog)))
            )
        return lines

    # -- runs out ------------------------------------------------------------------------

    def put(self, record: RunRecord) -> None:
        """Keep a finished run in the outbox, to be sent (a local write, on the loop)."""
        self.outbox.put(record)
        self.backlog += 1

    def sync_if_due(self) -> None:
        """Try the outbox again when runs wait in it and the last try is long enough ago."""
        if time.monotonic() >= self._next_sync and self.backlog:
            self.sync()

    def sync(self) -> None:
        """Send what waits in the outbox to the store, beside the loop (one sync at a time;
        the result is taken in by :meth:`poll`)."""
        self._next_sync = time.monotonic() + SYNC_EVERY_S
        self.backlog = self.outbox.count()
        self.set_aside = self.outbox.set_aside()
        if self._sync is not None:
            return
        if not self.backlog:
            self._store_says(None)
            return
        self._sync_started = time.monotonic()
        self._sync = self._sender.submit(self._send)

    def _send(self, store: RunStore | None) -> _Synced:
        """In the sender's thread: one pass over the outbox."""
        if store is None:
            return _Synced(error=f"results store unreachable ({self._sender.unavailable})")
        try:
            result = self.outbox.sync(store)
        except (StoreError, OSError) as exc:  # OSError: the outbox's own disk
            self._sender.drop()
            return _Synced(error=str(exc) if isinstance(exc, StoreError) else type(exc).__name__)
        if result.error is not None:
            self._sender.drop()
        return _Synced(result)

    # -- what the store knows of a unit ---------------------------------------------------

    def look_up(self, serial: str, *, gyro: bool) -> None:
        """Ask, beside the loop, what the store knows of ``serial`` (its stored fit too,
        with ``gyro``); :meth:`looked_up` gives the answer once it is there."""
        if serial in self._lookups:
            return
        pending = self.outbox.pending()
        self._lookups[serial] = self._reader.submit(
            lambda store: self._look_up(store, serial, pending, gyro)
        )

    def looked_up(self, serial: str) -> UnitLookup | None:
        """The answer about ``serial``, once it is there (None: not yet)."""
        answer = self._lookups.get(serial)
        if answer is None or not answer.done():
            return None
        del self._lookups[serial]
        lookup = answer.result()
        if lookup.fit_note:
            self._say_line(lookup.fit_note)
        return lookup

    def _look_up(
        self, store: RunStore | None, serial: str, pending: Sequence[Path], gyro: bool
    ) -> UnitLookup:
        """In the reader's thread: the unit's history (store and outbox), reviews and fit."""
        history = UnitHistory.gather(serial, store, pending)
        if not gyro or store is None:
            return UnitLookup(history)
        try:
            fit = store.gyro_fit(serial)
        except StoreError as exc:
            note = f"gyro fit of {serial} unavailable ({exc}): K keeps its g-sensitivity"
            return UnitLookup(history, fit_note=note)
        if fit is None:
            return UnitLookup(history)
        try:
            return UnitLookup(history, fit.report.error_model().n_g)
        except NotIdentifiableError:
            note = f"gyro fit of {serial} is incomplete: K keeps its g-sensitivity"
            return UnitLookup(history, fit_note=note)

    # -- what only the station's memory holds ---------------------------------------------

    @property
    def syncing(self) -> bool:
        """Whether a sync is under way."""
        return self._sync is not None

    def in_memory(self) -> tuple[int, int]:
        """Finished runs and unit journals the disk refused: (runs, journals)."""
        journals = sum(1 for j in self.disk.journal_files if j.unwritten is not None)
        return len(self.outbox.unwritten), journals

    def rescue(self) -> Rescued | None:
        """Save what only the station's memory holds anywhere it can be (None: nothing)."""
        journals = [j.unwritten for j in self.disk.journal_files if j.unwritten is not None]
        return rescue(list(self.outbox.unwritten), journals, self.disk.data_dir)

    # -- the loop's part ------------------------------------------------------------------

    def poll(self) -> None:
        """Take in what the workers finished and say how it went; write again what the
        disk refused."""
        self._check_disk()
        opened = self._opened
        if opened is not None and opened.done():
            self._opened = None
            if opened.result():
                self._say_line(tr("results database: connected"))
            else:
                self._store_says(
                    tr(
                        "results database unreachable ({why}): runs will wait in the outbox",
                        why=self._sender.unavailable,
                    )
                )
        sync = self._sync
        if sync is None or not sync.done():
            return
        self._sync = None
        synced = sync.result()
        self.backlog = self.outbox.count()
        self.set_aside = self.outbox.set_aside()
        if synced.result is None:
            self._store_says(said_of(waiting(self.backlog), synced.error or ""))
        else:
            self.backlog = synced.result.pending
            self._store_says(synced.result.note())

    def _store_says(self, note: str | None) -> None:
        """Show ``note`` about the store; a changed note also goes to the log."""
        if note is not None and note != self.store_note:
            self._say_line(note)
        self.store_note = note

    def _check_disk(self) -> None:
        """Write again what the disk refused; say what is still refused."""
        note = self.disk.check()
        if note is not None and note != self.disk_note:
            self._say_line(note)
        self.disk_note = note

    def open(self) -> None:
        """At start: reach the store (said once it answers) and send what waits in the
        outbox, beside the loop."""
        self._opened = self._sender.submit(lambda store: store is not None)
        self.sync()

    def close(self) -> None:
        """Finish the sync under way and send what is left (bounded by the store's own
        time-outs), then stop."""
        self._reader.close(wait=False)
        if self._sync is not None:
            self._sync.result()
            self.poll()
        if self.outbox.count():
            self._next_sync = 0.0
            self.sync()
            if self._sync is not None:
                self._sync.result()
            self.poll()
        self._sender.close(wait=True)
