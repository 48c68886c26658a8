"""Byte links the virtual putter serves: a pseudo-terminal or a TCP socket.

Both behave like a UART with a bounded transmit FIFO: bytes that nobody reads pile
up to :data:`TX_LIMIT` and whole writes beyond it are dropped, so a station that
stops reading never stalls the putter.
"""

import contextlib
import os
import socket
import tty
from pathlib import Path
from typing import Final, Protocol

TX_LIMIT: Final = 256 * 1024


class Link(Protocol):
    """What the putter needs from a transport."""

    url: str

    def fileno(self) -> int: ...
    def receive(self) -> bytes: ...
    def send(self, data: bytes) -> None: ...
    def flush(self) -> None: ...
    def close(self) -> None: ...


class _Outbox:
    def __init__(self) -> None:
        self.pending = bytearray()

    def add(self, data: bytes) -> None:
        if len(self.pending) + len(data) <= TX_LIMIT:
            self.pending += data


class PtyLink:
    """The master side of a new pty; the station opens :attr:`url` (the slave path).

    With ``alias``, a symlink of that name points to the slave, so the port keeps its
    name across :meth:`VirtualPutter.replug`; closed (the cable pulled), the link is gone,
    as a USB serial device's node is: the pty's number is free for another process, and
    a station reopening the name must not reach that process's unit.
    """

    def __init__(self, alias: Path | None = None) -> None:
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self._outbox = _Outbox()
        path = os.ttyname(self._slave)
        self._alias = alias
        self._slave_path = path
        if alias is not None:
            alias.unlink(missing_ok=True)
            alias.symlink_to(path)
            path = str(alias)
        self.url = path

    def fileno(self) -> int:
        return self._master

    def receive(self) -> bytes:
        try:
            return os.read(self._master, 4096)
        except (BlockingIOError, InterruptedError):
            return b""

    def send(self, data: bytes) -> None:
        self._outbox.add(data)
        self.flush()

    def flush(self) -> None:
        pending = self._outbox.pending
        while pending:
            try:
                written = os.write(self._master, pending)
            except (BlockingIOError, InterruptedError):
                return
            del pending[:written]

    def close(self) -> None:
        alias = self._alias
        if alias is not None and alias.is_symlink() and str(alias.readlink()) == self._slave_path:
            alias.unlink(missing_ok=True)
        os.close(self._master)
        os.close(self._slave)


class SocketLink:
    """A TCP server for one station at a time; the station opens ``socket://host:port``."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0) -> None:
        self._server = socket.create_server((host, port), reuse_port=False)
        self._server.setblocking(False)
        self._client: socket.socket | None = None
        self._outbox = _Outbox()
        self.host, self.port = self._server.getsockname()[:2]
        self.url = f"socket://{self.host}:{self.port}"

    def fileno(self) -> int:
        return (self._client or self._server).fileno()

    def _accept(self) -> None:
        if self._client is None:
            try:
                self._client, _ = self._server.accept()
            except BlockingIOError:
                return
            self._client.setblocking(False)
            self._client.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self._outbox.pending.clear()

    def _drop_client(self) -> None:
        if self._client is not None:
            self._client.close()
            self._client = None

    def receive(self) -> bytes:
        self._accept()
        if self._client is None:
            return b""
        try:
            data = self._client.recv(4096)
        except BlockingIOError:
            return b""
        except OSError:
            data = b""
        if not data:
            self._drop_client()
        return data

    def send(self, data: bytes) -> None:
        if self._client is not None:
            self._outbox.add(data)
            self.flush()

    def flush(self) -> None:
        pending = self._outbox.pending
        while pending and self._client is not None:
            try:
                sent = self._client.send(pending)
            except BlockingIOError:
                return
            except OSError:
                self._drop_client()
                return
            del pending[:sent]

    def close(self) -> None:
        self._drop_client()
        with contextlib.suppress(OSError):
            self._server.close()
