"""The data directory refusing writes mid-unit: one plain line, the unit kept in memory.

The journals (:class:`station.results.journal.JournalFile`, one per slot) and the outbox
(:class:`station.results.outbox.Outbox`) keep what the disk refused and write it again when
asked; :class:`DiskWatch` asks once a second and says, in the operator's words, what
is wrong and what to do, until every write went through.
"""

import errno
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from station.results.journal import JournalFile
from station.results.outbox import Outbox

#: Seconds between two attempts to write what the disk refused.
RETRY_EVERY_S = 1.0

#: errno → (what is wrong, what the operator does about it).
_PROBLEMS = {
    errno.ENOSPC: ("disk full", "free space"),
    errno.EDQUOT: ("disk quota exceeded", "free space"),
    errno.EFBIG: ("file too large for the disk", "free space"),
    errno.EROFS: ("read-only file system", "make it writable"),
    errno.EACCES: ("permission denied", "make it writable"),
    errno.EPERM: ("permission denied", "make it writable"),
}


def cannot_write_line(data_dir: Path, exc: OSError, kept: str) -> str:
    """The operator's line: what the disk refused, what is kept, what to do.

    ``disk full — the unit is kept in memory; free space in DATA_DIR to continue``: what
    is wrong comes first, so that a long data directory at a narrow screen's edge never
    hides it.
    """
    what, fix = _PROBLEMS.get(exc.errno or 0, (exc.strerror or str(exc), "fix it"))
    return f"{what} — {kept} kept in memory; {fix} in {data_dir} to continue"


class DiskWatch:
    """Retries the writes the disk refused and words the trouble for the screen."""

    def __init__(
        self,
        data_dir: Path,
        journal_files: Sequence[JournalFile],
        outbox: Outbox,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.data_dir = data_dir
        self.journal_files = tuple(journal_files)
        self.outbox = outbox
        self.clock = clock
        self._next_try = 0.0

    def check(self) -> str | None:
        """Retry (at most once a second) and return the line to show, None when all is written."""
        if self._journal_error() is None and self.outbox.write_error is None:
            return None
        now = self.clock()
        if now >= self._next_try:
            self._next_try = now + RETRY_EVERY_S
            for journal_file in self.journal_files:
                journal_file.retry()
            self.outbox.flush()
        error = self._journal_error() or self.outbox.write_error
        if error is None:
            return None
        runs = len(self.outbox.unwritten)
        units = sum(j.write_error is not None for j in self.journal_files)
        things = ["the unit" if units == 1 else f"{units} units"] if units else []
        things += [f"{runs} finished run{'s' * (runs > 1)}"] if runs else []
        verb = "is" if len(things) == 1 and runs <= 1 and units <= 1 else "are"
        return cannot_write_line(self.data_dir, error, f"{' and '.join(things)} {verb}")

    def _journal_error(self) -> OSError | None:
        return next((j.write_error for j in self.journal_files if j.write_error), None)
