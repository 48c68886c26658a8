"""A bounded, thread-safe buffer of sample rows between the reader thread and its user."""

import threading
from collections.abc import Callable

from station.domain.signals.samples import SampleBlock


class SampleBuffer:
    """Blocks of samples (:class:`~station.domain.signals.samples.SampleBlock`), at most
    ``capacity`` rows.

    The reader thread appends blocks; the user drains them. When nobody drains, the
    oldest rows are pushed out and counted in :attr:`overruns`.
    """

    def __init__(self, capacity: int) -> None:
        if capacity < 1:
            raise ValueError(f"buffer capacity must be positive, got {capacity}")
        self._capacity = capacity
        self._blocks: list[SampleBlock] = []
        self._rows = 0
        self._lock = threading.Lock()
        self._ready = threading.Condition(self._lock)
        self.overruns = 0

    def __len__(self) -> int:
        with self._lock:
            return self._rows

    def append(self, block: SampleBlock) -> None:
        """Add rows; drop the oldest beyond the capacity."""
        if not len(block):
            return
        with self._lock:
            self._blocks.append(block)
            self._rows += len(block)
            excess = self._rows - self._capacity
            while excess > 0:
                head = self._blocks[0]
                if len(head) <= excess:
                    self._blocks.pop(0)
                    cut = len(head)
                else:
                    self._blocks[0] = head[excess:]
                    cut = excess
                self._rows -= cut
                self.overruns += cut
                excess -= cut
            self._ready.notify_all()

    def drain(self, max_rows: int | None = None) -> SampleBlock:
        """Take up to ``max_rows`` (all by default) of the oldest rows."""
        with self._lock:
            rows = SampleBlock.concat(self._blocks)
            if max_rows is not None and max_rows < len(rows):
                taken, rest = rows[:max_rows], rows[max_rows:]
                self._blocks = [rest]
                self._rows = len(rest)
                return taken
            self._blocks = []
            self._rows = 0
            return rows

    def wait(self, rows: int, timeout: float, give_up: Callable[[], bool]) -> bool:
        """Block until ``rows`` rows are held, ``give_up()`` is true or ``timeout`` passes.

        Returns whether the rows are there.
        """
        with self._ready:
            self._ready.wait_for(lambda: self._rows >= rows or give_up(), timeout)
            return self._rows >= rows

    def wake(self) -> None:
        """Wake every waiter so it checks its ``give_up`` again (the link ended)."""
        with self._ready:
            self._ready.notify_all()
