"""Opening the putter's port: a pulled cable on a tty ends the reader, never kills it."""

import os
import pty
import threading

import pytest
import serial
from serial.threaded import Protocol, ReaderThread

from station.device.ports import TtyPort, open_port


def test_a_pty_opens_as_a_tty_port() -> None:
    master, slave = pty.openpty()
    try:
        port = open_port(os.ttyname(slave), baudrate=115200, timeout=0.01)
        assert isinstance(port, TtyPort)
        os.write(master, b"abc")
        port.read(3)
        port.close()
    finally:
        os.close(master)
        os.close(slave)


def test_a_pulled_cable_ends_the_reader_thread_through_connection_lost() -> None:
    """The cable pulled while the reader waits: the thread ends and its protocol hears of
    it, whichever of ``read`` and ``in_waiting`` meets the gone device first."""
    master, slave = pty.openpty()
    port = open_port(os.ttyname(slave), baudrate=115200, timeout=0.01)
    os.close(slave)
    lost = threading.Event()
    errors: list[BaseException | None] = []

    class Watcher(Protocol):
        def connection_lost(self, exc: BaseException | None) -> None:
            errors.append(exc)
            lost.set()

    reader = ReaderThread(port, Watcher)  # type: ignore[arg-type]
    reader.start()
    reader.connect()
    os.close(master)  # the cable is pulled
    assert lost.wait(timeout=30), "the reader never reported the lost connection"
    assert isinstance(errors[0], serial.SerialException)
    reader.join(timeout=30)
    assert not reader.is_alive()


def test_a_gone_device_is_a_serial_exception() -> None:
    """pyserial's own tty port raises a bare OSError (EIO) here, which the reader thread
    does not catch: it died without telling the link, and the station waited forever."""
    master, slave = pty.openpty()
    port = TtyPort(os.ttyname(slave), timeout=0.01)
    os.close(slave)
    os.close(master)
    with pytest.raises(serial.SerialException, match="device gone"):
        _ = port.in_waiting
    port.close()
