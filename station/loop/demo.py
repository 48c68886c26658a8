"""The demo's scripted operator and its virtual putters.

For each unit the operator takes a new virtual putter (its own seed, so its own true
offsets and sensitivities), plugs it into the station's port (a pty under a fixed
name), scans its serial number, and moves it into every pose the station asks for,
with the handling motion and settling tremor of a person. The station runs exactly
as on the line; only its keys come from here instead of a keyboard.
"""

import random
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from station.domain.sensors.sensor_spec import SensorSpec
from station.loop.keyboard import PolledKeys
from station.simulator.putter import VirtualPutter

#: Simulated seconds an operator takes to turn the putter into the next pose.
MOVE_S = 1.5


@dataclass
class DemoUnit:
    """One unit of the demo and the truth to compare the station's estimate with."""

    serial: str
    putter: VirtualPutter

    def truth(self) -> dict[str, Any]:
        """The unit's true offsets (counts) and sensitivities (counts/g) at 25 °C, and its
        gyro matrix K in body axes."""
        t = self.putter.truth
        return {
            "offset": dict(zip("xyz", map(float, t.offset_counts), strict=True)),
            "sensitivity": dict(zip("xyz", map(float, t.sensitivity_counts_per_g), strict=True)),
            "gyro_matrix": t.gyro_matrix.tolist(),
        }


def demo_serial(seed: int, number: int) -> str:
    """The serial number of the demo's unit ``number`` with ``seed``: ``PT001042``."""
    return f"PT{seed % 1000:03d}{number:03d}"


@dataclass
class CablePuller:
    """The demo operator's clumsy hand: at each move, with chance ``rate``, it pulls the
    unit's cable and plugs it back ``back_after_s`` wall seconds later (a demo of how the
    station carries on; ``calstation demo --pull-cables RATE``)."""

    rate: float = 0.0
    seed: int = 0
    back_after_s: float = 0.5
    pulls: int = 0
    _rng: random.Random = field(init=False)
    _out: list[tuple[float, VirtualPutter]] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._rng = random.Random(self.seed)

    def maybe_pull(self, putter: VirtualPutter) -> None:
        """Pull ``putter``'s cable, now and then."""
        if self.rate and self._rng.random() < self.rate:
            putter.unplug()
            self.pulls += 1
            self._out.append((time.monotonic() + self.back_after_s, putter))

    def plug_back(self) -> None:
        """Plug back every cable pulled long enough ago."""
        now = time.monotonic()
        for due in [entry for entry in self._out if entry[0] <= now]:
            self._out.remove(due)
            due[1].replug()


#: The demo operator's answers to the station's questions (see :class:`ScriptedOperator`).
ANSWERS = {"confirm": "y", "resume": "n"}


@dataclass
class ScriptedOperator(PolledKeys):
    """Plays the operator: plugs units in, scans them, moves them as asked.

    ``station`` is the :class:`station.loop.app.StationApp` it serves (set before its
    first :meth:`read`); ``port`` the pty name the station opens. A unit that passed in
    an earlier demo on the same data is calibrated again (y); a unit an earlier demo
    left interrupted is discarded (n): its virtual putter went with that process.
    """

    units: int
    port: Path
    seed: int = 0
    speed: float = 10.0
    #: The number of the demo's first unit: a demo run again on the same data takes new
    #: units (:func:`demo_serial`), as a line does.
    first: int = 1
    cables: CablePuller = field(default_factory=CablePuller)
    #: The sensor of the product the virtual putters are (default: the putter's).
    sensor: SensorSpec | None = None
    station: Any = None
    done: list[DemoUnit] = field(default_factory=list)
    _current: DemoUnit | None = None
    _moved_to: str | None = None

    def read(self) -> str:
        """The keys the operator types now; also moves the unit in the operator's hands."""
        app = self.station
        self.cables.plug_back()
        if app.prompt.state in ANSWERS:
            return ANSWERS[app.prompt.state]
        if app.prompt.state == "serial":
            if self._current is not None:
                self._current.putter.close()
                self.done.append(self._current)
                self._current = None
            if len(self.done) >= self.units:
                raise EOFError
            return self._next_unit() + "\n"
        run = app.run
        if run is not None and self._current is not None:
            target = run.requested
            if target is not None and target.name != self._moved_to:
                self._moved_to = target.name
                putter = self._current.putter
                if (putter.orientation.inv() * target.rotation).magnitude() > 1e-9:
                    putter.move_to(target.name, MOVE_S)
                self.cables.maybe_pull(putter)
        return ""

    def _next_unit(self) -> str:
        number = self.first + len(self.done)
        serial = demo_serial(self.seed, number)
        putter = VirtualPutter(
            seed=self.seed * 1000 + number, serial=serial, speed=self.speed, sensor=self.sensor
        )
        self.port.parent.mkdir(parents=True, exist_ok=True)
        putter.serve_pty(self.port)
        self._current = DemoUnit(serial, putter)
        self._moved_to = None
        return serial

    def close(self) -> None:
        """Unplug whatever unit is still connected."""
        if self._current is not None:
            self._current.putter.close()
            self.done.append(self._current)
            self._current = None
