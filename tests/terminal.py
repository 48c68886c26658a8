"""A ``calstation`` process in a real terminal (pexpect), waited on by what it shows.

The tests wait for the station's own progress, the screen text they expect, never for
a number of seconds: under load a station takes as long as it takes (a busy two-core
machine once needed over 30 s to show its first prompt). :data:`HUNG_STATION_S` only
ends a station that hangs; it is not a speed check. The same bound stands for the
waits on the station's files and database (:func:`wait_until`), and the test's own
``pytest-timeout`` (:data:`HUNG_TEST_S`) lies above it so that a hang is reported with
the screen the station showed.
"""

import time
from collections.abc import Callable, Sequence
from pathlib import Path

import pexpect
import pytest

#: Seconds a station may show nothing of what is expected before it counts as hung.
HUNG_STATION_S = 300
#: A terminal test's own hang guard (``pytest-timeout``), above the station's.
HUNG_TEST_S = 2 * HUNG_STATION_S
#: The ``pytest-timeout`` mark of a module of terminal tests.
hang_guard = pytest.mark.timeout(HUNG_TEST_S)


def spawn(argv: Sequence[str], *, env: dict[str, str], cwd: Path) -> pexpect.spawn:
    """``argv`` in a 60×140 terminal, UTF-8; each ``expect`` waits for its text, or
    :data:`HUNG_STATION_S` for a hung station. A character torn on the terminal reads as
    U+FFFD, as a terminal shows it: Ctrl-C can stop a write of the screen between the
    bytes of a wide character."""
    return pexpect.spawn(
        argv[0],
        list(argv[1:]),
        env=env,
        cwd=str(cwd),
        encoding="utf-8",
        codec_errors="replace",
        dimensions=(60, 140),
        timeout=HUNG_STATION_S,
    )


def wait_until(done: Callable[[], bool], what: str, *, tick: Callable[[], object]) -> None:
    """Call ``tick`` (e.g. read the screen, so that the station never blocks on its
    terminal) until ``done()``; fail naming ``what`` after :data:`HUNG_STATION_S`."""
    deadline = time.monotonic() + HUNG_STATION_S
    while not done():
        if time.monotonic() > deadline:
            pytest.fail(f"hung: {what} not seen in {HUNG_STATION_S} s")
        tick()
