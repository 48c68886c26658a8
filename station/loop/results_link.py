"""The station's way to its results: the outbox, the results store, the data disk.

:class:`ResultsLink` hands every finished run to the outbox, empties the outbox into
the results store when it can (at start, after each unit, and every
:data:`SYNC_EVERY_S` while idle), reconnects to the store after it failed, asks the
disk watch to write again what the disk refused, and keeps, in one line each, what the
operator is told about the store and the disk. The unit lifecycle
(:class:`station.loop.lifecycle.UnitLifecycle`) owns it; the front-ends read its lines.
"""

import time
from collections.abc import Callable, Sequence
from pathlib import Path

from rich.console import RenderableType
from rich.text import Text

from station.domain.arrays import FloatArray
from station.domain.gyro import NotIdentifiableError
from station.domain.records import RunRecord
from station.loop.unit_history import UnitHistory
from station.results.disk import DiskWatch
from station.results.journal import JournalFile
from station.results.outbox import Outbox, waiting
from station.results.storage import RunStore, StoreError

#: Seconds between attempts to empty a non-empty outbox while idle.
SYNC_EVERY_S = 5.0


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
        self._open_store = open_store
        self._store: RunStore | None = None
        self._say_line = say_line
        self._next_sync = 0.0
        self.store_note: str | None = None
        #: Runs waiting in the outbox (counted at every sync, kept up to date between).
        self.backlog = 0
        #: Outbox files set aside: (unreadable, refused), counted at every sync.
        self.set_aside = (0, 0)
        self.disk = DiskWatch(data_dir, journal_files, self.outbox)
        #: What the disk refused, in one line (None when every write went through).
        self.disk_note: str | None = None

    def status_lines(self) -> list[RenderableType]:
        """What the disk refuses and how the store fares, for the top of the screen."""
        lines: list[RenderableType] = []
        if self.disk_note:
            lines.append(Text(self.disk_note, style="bold red"))
        if self.store_note:
            lines.append(Text(self.store_note, style="yellow"))
        return lines

    def put(self, record: RunRecord) -> None:
        """Keep a finished run in the outbox, to be sent."""
        self.outbox.put(record)
        self.backlog += 1

    def history(self, serial: str) -> UnitHistory:
        """The unit's runs, from the store (if reachable) and the outbox."""
        if self._store is None:
            self.check_store()
        return UnitHistory.gather(serial, self._store, self.outbox.pending())

    def g_sensitivity(self, serial: str) -> FloatArray | None:
        """The scale-factor g-sensitivity ``N`` (3×3, 1/g) of the unit's stored
        [Park2014]_ fit, for the gyro matrix (None: no fit, or the store cannot say)."""
        if self._store is None:
            self.check_store()
        if self._store is None:
            return None
        try:
            fit = self._store.gyro_fit(serial)
        except StoreError as exc:
            self._say_line(f"gyro fit of {serial} unavailable ({exc}): K keeps its g-sensitivity")
            return None
        if fit is None:
            return None
        try:
            return fit.report.error_model().n_g
        except NotIdentifiableError:
            self._say_line(f"gyro fit of {serial} is incomplete: K keeps its g-sensitivity")
            return None

    def sync_if_due(self) -> None:
        """Try the outbox again when runs wait in it and the last try is long enough ago."""
        if time.monotonic() >= self._next_sync and self.backlog:
            self.sync()

    def sync(self) -> None:
        """Send what waits in the outbox to the store, and say how it went."""
        self._next_sync = time.monotonic() + SYNC_EVERY_S
        self.backlog = self.outbox.count()
        self.set_aside = self.outbox.set_aside()
        if not self.backlog:
            self._store_says(None)
            return
        try:
            if self._store is None:
                self._store = self._open_store()
            result = self.outbox.sync(self._store)
        except (StoreError, OSError) as exc:  # OSError: the outbox's own disk
            self._drop_store()
            reason = str(exc) if isinstance(exc, StoreError) else type(exc).__name__
            self._store_says(f"{waiting(self.backlog)}: results store unreachable ({reason})")
            return
        self.backlog = result.pending
        self.set_aside = self.outbox.set_aside()
        if result.error is not None:
            self._drop_store()
        self._store_says(result.note())

    def _store_says(self, note: str | None) -> None:
        """Show ``note`` about the store; a changed note also goes to the log."""
        if note is not None and note != self.store_note:
            self._say_line(note)
        self.store_note = note

    def check_disk(self) -> None:
        """Write again what the disk refused; say what is still refused."""
        note = self.disk.check()
        if note is not None and note != self.disk_note:
            self._say_line(note)
        self.disk_note = note

    def check_store(self) -> None:
        """Connect to the store at start, so the first unit does not wait for it."""
        try:
            self._store = self._open_store()
        except StoreError as exc:
            self.store_note = f"results database unreachable ({exc}): runs will wait in the outbox"
            self._say_line(self.store_note)
        else:
            self._say_line("results database: connected")

    def _drop_store(self) -> None:
        if self._store is not None:
            self._store.close()
            self._store = None

    def close(self) -> None:
        """Close the store's connection, if open."""
        self._drop_store()
