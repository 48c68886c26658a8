"""A line-based control channel for a virtual putter running in its own process.

A test that drives the station through a real terminal moves the unit from outside
by writing lines to ``calstation simulate``'s standard input; every line gets one
reply line, ``ok [detail]`` or ``error <message>``::

    pose NAME [SECONDS]   start moving to a named pose (default 1.5 s); while
                          streaming, answers "ok from_seq N": the first sample
                          number the move can show in
    settle                wait until the last move's tremor has died down
    wait SECONDS          let simulated time pass
    unplug | replug       pull / plug back the cable (replug answers the URL)
    fault NAME VALUE      set a fault (see Faults), e.g. "fault drop_rate 0.02"
    faults | truth | calibration | url | help
    quit                  stop the simulator
"""

import json
from collections.abc import Callable
from typing import Final

from pydantic import ValidationError

from station.domain.sensors.faults import Faults
from station.domain.signals.poses import POSES
from station.simulator.putter import VirtualPutter

HELP: Final = (
    "commands: pose NAME [SECONDS], settle, wait SECONDS, unplug, replug, "
    "fault NAME VALUE, faults, truth, calibration, url, quit"
)
_NONE_WORDS: Final = frozenset({"none", "off", "null"})


def _number(text: str, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"{what} must be a number, got {text!r}") from None
    if not value >= 0:
        raise ValueError(f"{what} must not be negative, got {text!r}")
    return value


class ControlChannel:
    """Turns control lines into actions on ``putter``."""

    def __init__(self, putter: VirtualPutter) -> None:
        self.putter = putter
        #: Set by ``quit``: the controller wants the simulator stopped.
        self.quit = False
        self._commands: dict[str, Callable[[list[str]], str]] = {
            "pose": self._pose,
            "settle": self._settle,
            "wait": self._wait,
            "unplug": self._unplug,
            "replug": self._replug,
            "fault": self._fault,
            "faults": lambda _: self.putter.faults.model_dump_json(),
            "truth": lambda _: json.dumps(self.putter.truth.to_dict()),
            "calibration": self._calibration,
            "url": lambda _: self.putter.url or "unplugged",
            "help": lambda _: HELP,
        }

    def handle(self, line: str) -> str | None:
        """The reply to ``line`` (None for a blank line); ``quit`` sets :attr:`quit`."""
        words = line.split()
        if not words:
            return None
        name, args = words[0].lower(), words[1:]
        if name == "quit":
            self.quit = True
            return "ok"
        command = self._commands.get(name)
        if command is None:
            return f"error unknown command {name!r}; {HELP}"
        try:
            detail = command(args)
        except (ValueError, KeyError) as exc:
            return f"error {exc.args[0] if exc.args else exc}"
        return f"ok {detail}".rstrip()

    def _pose(self, args: list[str]) -> str:
        if not 1 <= len(args) <= 2:
            raise ValueError("usage: pose NAME [SECONDS]")
        if args[0] not in POSES:
            raise ValueError(f"unknown pose {args[0]!r}; known: {', '.join(POSES)}")
        seconds = _number(args[1], "move time") if len(args) == 2 else 1.5
        if seconds == 0:
            raise ValueError("move time must be positive")
        first = self.putter.move_to(args[0], seconds)
        return "" if first is None else f"from_seq {first}"

    def _settle(self, args: list[str]) -> str:
        self.putter.sleep(self.putter.settled_at_s - self.putter.clock.now())
        return ""

    def _wait(self, args: list[str]) -> str:
        if len(args) != 1:
            raise ValueError("usage: wait SECONDS")
        self.putter.sleep(_number(args[0], "wait time"))
        return ""

    def _unplug(self, args: list[str]) -> str:
        self.putter.unplug()
        return ""

    def _replug(self, args: list[str]) -> str:
        return self.putter.replug()

    def _fault(self, args: list[str]) -> str:
        if len(args) != 2:
            raise ValueError(f"usage: fault NAME VALUE; names: {', '.join(Faults.model_fields)}")
        name, value = args
        if name not in Faults.model_fields:
            raise ValueError(f"unknown fault {name!r}; known: {', '.join(Faults.model_fields)}")
        try:
            setattr(self.putter.faults, name, None if value.lower() in _NONE_WORDS else value)
        except ValidationError as exc:
            raise ValueError(f"fault {name}: {exc.errors()[0]['msg']}") from None
        return ""

    def _calibration(self, args: list[str]) -> str:
        cal = self.putter.stored_calibration
        return json.dumps(
            {"offset": cal.offset.tolist(), "matrix": cal.matrix.tolist(), "written": cal.written}
        )
