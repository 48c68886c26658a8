"""Opening the putter's port: any pyserial URL, with TCP made fit for a reader thread.

:class:`serial.threaded.ReaderThread` reads ``port.in_waiting or 1`` bytes at a time
and, on a port without ``cancel_read``, raises the read timeout to one second so that
its loop can notice a stop. pyserial's ``socket://`` port has both problems: its
``in_waiting`` says only whether *some* byte waits (pyserial issue #759), so the
thread would read 22-byte frames one byte per call, and it has no ``cancel_read``, so
closing an idle driver would take a second. :class:`SocketPort` fixes both. A tty's
``in_waiting`` (an ``ioctl``) raises a bare ``OSError`` (EIO) once the cable is pulled,
which the thread does not catch (it ends on a ``SerialException``), so the loss would
never reach the link: :class:`TtyPort` raises it as a ``SerialException``. Every other
URL (``loop://``, ``rfc2217://``) is opened by :func:`serial.serial_for_url` as is.
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


class TtyPort(serial.Serial):
    """A tty (or pty) whose ``in_waiting`` fails as a ``SerialException`` when the device
    is gone, as its ``read`` does."""

    @property
    def in_waiting(self) -> int:
        """Bytes waiting in the tty's input queue."""
        try:
            return int(super().in_waiting)
        except OSError as exc:
            raise serial.SerialException(f"{self.port}: device gone ({exc})") from exc


def open_port(url: str, *, baudrate: int, timeout: float) -> serial.SerialBase:
    """Open ``url`` (any :func:`serial.serial_for_url` URL) for a reader thread."""
    if url.startswith("socket://"):
        port = SocketPort(None, baudrate=baudrate, timeout=timeout)
        port.port = url
        port.open()
        return port
    if "://" not in url:  # a device path: a tty or pty
        return TtyPort(url, baudrate=baudrate, timeout=timeout)
    return serial.serial_for_url(url, baudrate=baudrate, timeout=timeout)
