"""The operator's keys, read without blocking the station's loop.

On a terminal the station puts it in cbreak mode (each key arrives at once, nothing
echoed) and restores it on exit; a barcode scanner is a keyboard that types the
serial number and Enter. Without a terminal (a pipe), whatever arrived is read as is.
Between its passes the loop waits on the keys (:meth:`KeySource.wait`): a key ends the
wait, so what is typed is echoed at once however seldom the loop passes otherwise.
"""

import os
import select
import sys
import termios
import time
import tty
from types import TracebackType
from typing import Any, Protocol, Self

CTRL_D = b"\x04"


class KeySource(Protocol):
    """Where the station's keys come from."""

    def read(self) -> str:
        """The characters typed since the last call ('' for none); never blocks.

        Raises :class:`EOFError` once the source is closed.
        """
        ...

    def wait(self, timeout: float) -> None:
        """Return once a key may have come, or after ``timeout`` seconds."""
        ...


class PolledKeys:
    """A key source with nothing to wait on (a script, the demo's operator): the loop
    just rests between its passes."""

    def wait(self, timeout: float) -> None:
        """Rest ``timeout`` seconds."""
        time.sleep(timeout)


class TerminalKeys:
    """Keys from standard input (or the file descriptor ``fd``), in cbreak mode while used
    as a context manager."""

    def __init__(self, fd: int | None = None) -> None:
        self.fd = sys.stdin.fileno() if fd is None else fd
        self._saved: list[Any] | None = None
        #: Standard input has ended: it reads as ready for ever, so waiting on it would
        #: spin (the station may go on a while after Ctrl-D, storing what it holds).
        self._ended = False

    def __enter__(self) -> Self:
        if os.isatty(self.fd):
            self._saved = termios.tcgetattr(self.fd)
            tty.setcbreak(self.fd)
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        if self._saved is not None:
            termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)

    def wait(self, timeout: float) -> None:
        """Return once standard input holds a key, or after ``timeout``."""
        if self._ended:
            time.sleep(timeout)
        else:
            select.select([self.fd], [], [], timeout)

    def read(self) -> str:
        chunks: list[bytes] = []
        while select.select([self.fd], [], [], 0)[0]:
            data = os.read(self.fd, 1024)
            if not data:
                if chunks:
                    break
                self._ended = True
                raise EOFError
            if CTRL_D in data:  # in cbreak mode the terminal no longer turns it into EOF
                raise EOFError
            chunks.append(data)
        return b"".join(chunks).decode("utf-8", errors="replace")
