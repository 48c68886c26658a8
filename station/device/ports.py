"""Opening the putter's port: any pyserial URL, with TCP made fit for a reader thread.

:class:`serial.threaded.ReaderThread` reads ``port.in_waiting or 1`` bytes at a time
and, on a port without ``cancel_read``, raises the read timeout to one second so that
its loop can notice a stop. pyserial's ``socket://`` port has both problems: its
``in_waiting`` says only whether *some* byte waits (pyserial issue #759), so the
thread would read 22-byte frames one byte per call, and it has no ``cancel_read``, so
closing an idle driver would take a second. :class:`SocketPort` fixes both; every
other URL (a tty, a pty, ``loop://``) is opened by :func:`serial.serial_for_url` as is.
"""

import contextlib
import fcntl
import socket
import struct
import termios

import serial
from serial.urlhandler.protocol_socket import Serial as _PyserialSocket

_INT = struct.Struct("i")


class SocketPort(_PyserialSocket):
    """pyserial's ``socket://`` port with a byte-exact ``in_waiting`` and ``cancel_read``."""

    _socket: socket.socket  # set by pyserial's open()

    @property
    def in_waiting(self) -> int:
        """Bytes queued in the socket's receive buffer (FIONREAD), as a tty reports them."""
        if not self.is_open:
            raise serial.PortNotOpenError()
        queued = fcntl.ioctl(self._socket.fileno(), termios.FIONREAD, _INT.pack(0))
        return int(_INT.unpack(queued)[0])

    def cancel_read(self) -> None:
        """End a blocked read: shut the socket's receiving side (the port is being closed)."""
        if self.is_open:
            with contextlib.suppress(OSError):
                self._socket.shutdown(socket.SHUT_RD)


def open_port(url: str, *, baudrate: int, timeout: float) -> serial.SerialBase:
    """Open ``url`` (any :func:`serial.serial_for_url` URL) for a reader thread."""
    if url.startswith("socket://"):
        port = SocketPort(None, baudrate=baudrate, timeout=timeout)
        port.port = url
        port.open()
        return port
    return serial.serial_for_url(url, baudrate=baudrate, timeout=timeout)
