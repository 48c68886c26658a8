"""``calstation simulate``: a virtual putter on a pty or a TCP port, in its own process.

It prints ``url <URL>`` on standard output, then reads control lines from standard
input (see :mod:`station.simulator.control`) and answers each with one line. When
standard input ends it keeps serving until interrupted or terminated.
"""

# Light to import: --help and refused arguments read only the signatures below;
# each command imports its work (numpy, SQLAlchemy, the loop, ...) when it runs.

import signal
import sys
import threading
from pathlib import Path
from types import FrameType
from typing import Annotated

import typer
from pydantic import ValidationError

from station.cli.output import out
from station.domain.constants import DEFAULT_RATE_HZ, MAX_RATE_HZ
from station.domain.errors import InputError
from station.domain.sensors.faults import Faults


def _address(listen: str) -> tuple[str, int]:
    host, sep, port = listen.rpartition(":")
    if not sep or not host or not port.isdigit() or int(port) > 65535:
        raise InputError(f"--listen: expected HOST:PORT, got {listen!r}")
    return host, int(port)


def _faults(items: list[str]) -> Faults:
    values: dict[str, str | None] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep:
            raise InputError(f"--fault: expected NAME=VALUE, got {item!r}")
        values[name] = None if value.lower() in ("none", "off") else value
    try:
        return Faults.model_validate(values)
    except ValidationError as exc:
        first = exc.errors()[0]
        field = ".".join(str(p) for p in first["loc"])
        raise InputError(f"--fault {field}: {first['msg']}") from None


def _say(line: str) -> None:
    out.print(line, markup=False, highlight=False)
    out.file.flush()


def simulate(
    pty: Annotated[bool, typer.Option("--pty", help="serve on a new pseudo-terminal")] = False,
    link: Annotated[
        Path | None, typer.Option(help="with --pty: symlink the pty here (stable across replug)")
    ] = None,
    listen: Annotated[
        str | None, typer.Option(metavar="HOST:PORT", help="serve socket:// on this address")
    ] = None,
    seed: Annotated[int, typer.Option(help="fixes the unit's parameters and noise")] = 0,
    serial: Annotated[str, typer.Option(help="serial number on the unit's label")] = "PT000001",
    speed: Annotated[float, typer.Option(help="simulated seconds per real second")] = 1.0,
    rate: Annotated[int, typer.Option(help="initial sample rate, samples/s")] = DEFAULT_RATE_HZ,
    start_pose: Annotated[str, typer.Option(help="pose the unit lies in at start")] = "face_up",
    fault: Annotated[
        list[str] | None,
        typer.Option(help="NAME=VALUE, repeatable: " + ", ".join(Faults.model_fields)),
    ] = None,
) -> None:
    """Run a virtual putter that speaks the station's serial protocol."""
    from station.domain.signals.poses import POSES
    from station.simulator.control import ControlChannel
    from station.simulator.putter import VirtualPutter

    if pty == (listen is not None):
        raise InputError("give exactly one of --pty or --listen HOST:PORT")
    if not speed > 0:
        raise InputError(f"--speed must be positive, got {speed}")
    if not 1 <= rate <= MAX_RATE_HZ:
        raise InputError(f"--rate must be 1…{MAX_RATE_HZ} samples/s, got {rate}")
    if start_pose not in POSES:
        raise InputError(f"--start-pose: unknown pose {start_pose!r}; known: {', '.join(POSES)}")
    if len(serial.encode()) > 16 or not serial.isascii() or not serial:
        raise InputError(f"--serial: 1 to 16 ASCII characters, got {serial!r}")
    faults = _faults(fault or [])
    putter = VirtualPutter(
        seed=seed, serial=serial, rate_hz=rate, speed=speed, faults=faults, start_pose=start_pose
    )
    try:
        url = putter.serve_pty(link) if pty else putter.serve_socket(*_address(listen or ""))
    except OSError as exc:
        raise InputError(f"cannot serve the virtual putter: {exc}") from None
    done = threading.Event()

    def stop(signum: int, frame: FrameType | None) -> None:
        done.set()

    signal.signal(signal.SIGTERM, stop)
    _say(f"url {url}")
    channel = ControlChannel(putter)
    try:
        for line in sys.stdin:
            reply = channel.handle(line)
            if reply is not None:
                _say(reply)
            if channel.quit:
                break
        else:
            done.wait()
    except KeyboardInterrupt:
        pass
    finally:
        putter.close()
        if link is not None and pty:
            link.unlink(missing_ok=True)
