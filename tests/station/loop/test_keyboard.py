"""The operator's keys on standard input: a key ends the loop's wait at once; once the
input has ended, the wait rests instead of spinning."""

import contextlib
import os
import threading
import time
from collections.abc import Iterator

import pytest

from station.loop.keyboard import TerminalKeys

#: A hang guard, not a speed requirement.
HANG_S = 60.0


@pytest.fixture
def piped() -> Iterator[tuple[TerminalKeys, int]]:
    """Keys read from a pipe (as the station reads a piped standard input), and the pipe's
    writing end."""
    read_end, write_end = os.pipe()
    keys = TerminalKeys(read_end)
    try:
        yield keys, write_end
    finally:
        os.close(read_end)
        with contextlib.suppress(OSError):  # a test may have closed it
            os.close(write_end)


def test_a_key_ends_the_wait_at_once(piped: tuple[TerminalKeys, int]) -> None:
    keys, write_end = piped
    waiting = threading.Thread(target=keys.wait, args=(3600.0,), daemon=True)
    waiting.start()
    os.write(write_end, b"P")
    waiting.join(HANG_S)
    assert not waiting.is_alive()
    assert keys.read() == "P"


def test_once_the_input_has_ended_the_wait_rests_for_its_timeout(
    piped: tuple[TerminalKeys, int],
) -> None:
    keys, write_end = piped
    os.close(write_end)
    with pytest.raises(EOFError):
        keys.read()
    start = time.monotonic()
    keys.wait(0.2)
    assert time.monotonic() - start >= 0.2  # an ended pipe reads as ready: no spinning
