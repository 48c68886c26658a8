"""What the station proves about its surroundings before it takes a unit.

The configuration's values are checked where they are read (:mod:`station.loop.config`);
these checks are about the machine: the data directory takes a durable write (not
read-only, not full) and the putter port is there. Each failure is one
:class:`InputError` line and exit status 2, before any unit is scanned: a station that
cannot keep a journal or reach a port would otherwise fail in the middle of a unit.
"""

import os
import stat
from collections.abc import Sequence
from pathlib import Path
from urllib.parse import urlsplit

import serial

from station.domain.errors import InputError
from station.domain.i18n import tr
from station.results.files import disk_problem, write_atomic

#: Room the data directory must have at start: a unit's journal and its run record
#: (tens of KiB each), so the first unit can be journaled and kept.
PROBE_BYTES = 64 * 1024
PROBE_NAME = ".calstation-probe"


def prepare_data_dir(path: Path) -> None:
    """Make the data directory and prove it durably takes :data:`PROBE_BYTES`."""
    directory = path.expanduser()
    probe = directory / PROBE_NAME
    try:
        directory.mkdir(parents=True, exist_ok=True)
        write_atomic(probe, "0" * PROBE_BYTES)
        probe.unlink()
    except OSError as exc:
        raise InputError(
            tr(
                "data directory {directory}: {problem}: the station cannot keep "
                "its journal and outbox there",
                directory=directory,
                problem=disk_problem(exc),
            )
        ) from None


def check_port(port: str | None) -> None:
    """The putter port is configured and names something that can be a serial port.

    A device path must exist and be a character device the user may open. A URL
    (``socket://host:port``, ``rfc2217://…``) must be well formed; a server that does
    not answer yet is not refused here: like a unit not yet plugged in, the station
    says so and tries again at every scan.
    """
    if not port:
        raise InputError(tr("no putter port: give --port or set port in the station configuration"))
    if "://" in port:
        try:
            serial.serial_for_url(port, do_not_open=True)
        except (ValueError, serial.SerialException) as exc:
            raise InputError(f"port {port}: {exc}") from None
        _check_network_address(port)
        return
    try:
        mode = os.stat(port).st_mode
    except OSError as exc:
        if isinstance(exc, FileNotFoundError):
            raise InputError(
                tr(
                    "port {port}: no such device (is the adapter plugged in? check --port)",
                    port=port,
                )
            ) from None
        raise InputError(f"port {port}: {disk_problem(exc)}") from None
    if not stat.S_ISCHR(mode):
        raise InputError(tr("port {port}: not a serial device", port=port))
    if not os.access(port, os.R_OK | os.W_OK):
        raise InputError(
            tr("port {port}: permission denied (the user needs the dialout group)", port=port)
        )


def check_slot_ports(ports: Sequence[str]) -> list[str]:
    """The fixture's ports: one line for each slot whose port is not there now.

    A port that could never be one (a malformed URL) stops the station
    (:class:`InputError`); a device that is missing or refused is only said (a unit's
    USB port may appear only once it is plugged in): its unit cannot be reached until it
    is there, and the other slots go on.
    """
    lines = []
    for number, port in enumerate(ports, start=1):
        if "://" in port:
            check_port(port)
            continue
        try:
            check_port(port)
        except InputError as exc:
            lines.append(
                tr("slot {number}: {problem}: the other slots go on", number=number, problem=exc)
            )
    return lines


def _check_network_address(port: str) -> None:
    """A ``socket://`` or ``rfc2217://`` URL names a host and a TCP port."""
    parts = urlsplit(port)
    if parts.scheme not in ("socket", "rfc2217"):
        return
    try:
        number = parts.port
    except ValueError:
        number = None
    if not parts.hostname or not number:
        raise InputError(f"port {port}: expected {parts.scheme}://HOST:PORT (PORT 1 to 65535)")
