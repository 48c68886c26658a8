"""Per-record exponential backoff for the outbox, kept in memory.

A record the store keeps failing on (a 500, a database error on its rows) is tried
again after 5 s, then 10 s, 20 s, … up to 5 minutes between tries, while the records
behind it are sent at once. The state lives in memory only: after a restart every
record gets one immediate try again, which costs one request each and keeps no
sidecar file to go stale or to fail on a full disk.
"""

import time
from collections.abc import Callable
from dataclasses import dataclass

#: Seconds before the first retry of a failing record; doubles with every failure.
FIRST_S = 5.0
#: Longest wait between two tries of one record.
LONGEST_S = 300.0


@dataclass
class _Retry:
    failures: int
    next_try: float
    reason: str


class RecordBackoff:
    """When each failing record (by name) may be tried again."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self.clock = clock
        self._failing: dict[str, _Retry] = {}

    def due(self, name: str) -> bool:
        """Whether record ``name`` may be sent now."""
        failing = self._failing.get(name)
        return failing is None or self.clock() >= failing.next_try

    def failed(self, name: str, reason: str) -> float:
        """Record one more failure of ``name``; return the seconds until its next try."""
        failures = self._failing[name].failures + 1 if name in self._failing else 1
        wait = min(FIRST_S * 2.0 ** (failures - 1), LONGEST_S)
        self._failing[name] = _Retry(failures, self.clock() + wait, reason)
        return wait

    def forget(self, name: str) -> None:
        """``name`` was stored, refused or set aside: no more backoff."""
        self._failing.pop(name, None)

    def reasons(self, names: set[str]) -> dict[str, str]:
        """The last failure of each of ``names`` still failing."""
        return {n: f.reason for n, f in self._failing.items() if n in names}
