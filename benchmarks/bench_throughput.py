"""Units per operator-hour for 1, 2, 4 and 8 slots, fixed and adaptive capture.

    python benchmarks/bench_throughput.py                 # 2 cycles per row, at 5×
    python benchmarks/bench_throughput.py --cycles 1      # quicker
    python benchmarks/bench_throughput.py --speed 1 --slots 8 --capture fixed --cycles 1

A plant buys a station on units per operator-hour. Each row runs the real station on
virtual putters over real ptys: the one-port station (:class:`station.app.StationApp`
with the demo's scripted operator) for one slot, the fixture
(:class:`station.fixture.app.FixtureApp` with :class:`station.fixture.demo.FixtureOperator`,
each unit with its own mounting misalignment) for several, storing into SQLite.

**Device time** is read from the units' own sequence numbers, so it does not depend on
the virtual speed or on this machine: for each pose and unit, from the end of the move
into the pose (the move's first sample plus its duration) to the last sample of the
accepted window; for the first pose, from the unit's stream start (its scan) to its
window's last sample. A fixture's pose lasts as long as its slowest slot; then each
unit checks its own output (256 calibrated samples, 0.51 s, in parallel).

**Operator time** is added as stated below (``OPERATOR``), not simulated: loading,
scanning and unloading each unit, and the moves between the seven poses (six moves).

**Station time**: the station's CPU per unit (process CPU minus the virtual putters'
threads), counted once per unit in the cycle as if nothing of it overlapped.

    cycle = K × (load + scan + unload) + 6 × move(K) + Σ_pose max_slot(device) + 0.51 s
            + K × station CPU per unit
    units per operator-hour = 3600 × K / cycle
"""

import argparse
import statistics
import tempfile
import time
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rich.console import Console

from station.acquisition.pose import PoseResult
from station.app import StationApp
from station.config import StationConfig
from station.demo import MOVE_S, ScriptedOperator
from station.device import DEFAULT_RATE_HZ
from station.fixture.app import FixtureApp
from station.fixture.demo import FixtureOperator
from station.limits import load_profile
from station.run.settings import RunSettings
from station.run.unit_output import UNIT_OUTPUT_SAMPLES
from station.session import UnitRun
from station.simulator.putter import VirtualPutter
from station.storage import DatabaseStore

#: Stated operator times, seconds (see docs/benchmarks.md, "throughput", for where from).
OPERATOR = {
    "load": 2.0,  # take the unit from the tray, seat it, plug its cable
    "scan": 1.5,  # aim the hand scanner at the label, beep
    "unload": 1.5,  # unplug, put it where the screen says
}
#: Seconds to move into the next pose: one putter in the hand (the demo's scripted
#: operator), or the fixture box turned onto its next face, whatever it holds.
MOVE_ONE_S = MOVE_S
MOVE_FIXTURE_S = 3.0
POSES = 7


@dataclass
class Unit:
    """What one unit's stream showed: moves (first sequence number, seconds) and captures."""

    moves: list[tuple[int, float]] = field(default_factory=list)
    captures: list[int] = field(default_factory=list)

    def pose_device_s(self, rate: float) -> list[float]:
        """Device seconds of each pose: from the end of its move to its window's last sample."""
        times = [(self.captures[0] + 1) / rate]
        for last in self.captures[1:]:
            first, seconds = max((m for m in self.moves if m[0] <= last), key=lambda m: m[0])
            times.append((last + 1 - first) / rate - seconds)
        return times


@dataclass
class Events:
    """Units by port, in the order they were plugged in; CPU of the putters' threads."""

    units: dict[str, list[Unit]] = field(default_factory=lambda: defaultdict(list))
    putter_cpu_s: float = 0.0


def instrument(events: Events) -> Callable[[], None]:
    """Note plug-ins, moves, accepted captures and the putters' CPU; returns the undo."""
    serve_pty = VirtualPutter.serve_pty
    move_to = VirtualPutter.move_to
    close = VirtualPutter.close
    accept = UnitRun._accept

    def serve(self: VirtualPutter, alias: Any = None) -> str:
        url = serve_pty(self, alias)
        events.units[url].append(Unit())
        return url

    def move(self: VirtualPutter, target: Any, duration_s: float = 1.5, **kw: Any) -> int | None:
        first = move_to(self, target, duration_s, **kw)
        if first is not None and self.url is not None:
            events.units[self.url][-1].moves.append((first, duration_s))
        return first

    def closed(self: VirtualPutter) -> None:
        thread = self._thread
        if thread is not None and thread.ident is not None and thread.is_alive():
            events.putter_cpu_s += time.clock_gettime(time.pthread_getcpuclockid(thread.ident))
        close(self)

    def accepted(self: UnitRun, result: PoseResult, target: Any) -> None:
        events.units[self.driver.url][-1].captures.append(result.last_seq)
        accept(self, result, target)

    VirtualPutter.serve_pty = serve  # type: ignore[method-assign]
    VirtualPutter.move_to = move  # type: ignore[method-assign]
    VirtualPutter.close = closed  # type: ignore[method-assign]
    UnitRun._accept = accepted  # type: ignore[method-assign]

    def undo() -> None:
        VirtualPutter.serve_pty = serve_pty  # type: ignore[method-assign]
        VirtualPutter.move_to = move_to  # type: ignore[method-assign]
        VirtualPutter.close = close  # type: ignore[method-assign]
        UnitRun._accept = accept  # type: ignore[method-assign]

    return undo


def run_station(data: Path, slots: int, cycles: int, capture: str, speed: float) -> list[Any]:
    """The station on ``slots × cycles`` virtual units; their records."""
    units = slots * cycles
    database = f"sqlite:///{data}/results.sqlite3"
    run = RunSettings(capture=capture)  # type: ignore[arg-type]
    common: dict[str, Any] = {
        "profile": load_profile(),
        "console": Console(quiet=True),
        "units": units,
    }
    operator: ScriptedOperator | FixtureOperator
    app: StationApp | FixtureApp
    if slots == 1:
        port = data / "putter"
        config = StationConfig(data_dir=data, port=str(port), database_url=database, run=run)
        operator = ScriptedOperator(units=units, port=port, seed=11, speed=speed)
        app = StationApp(
            config=config,
            open_store=lambda: DatabaseStore(database),
            keys=operator,
            probe_port=False,
            **common,
        )
    else:
        ports = [data / f"putter-slot{n}" for n in range(1, slots + 1)]
        config = StationConfig(
            data_dir=data, slots=tuple(map(str, ports)), database_url=database, run=run
        )
        operator = FixtureOperator(units=units, ports=ports, seed=11, speed=speed)
        app = FixtureApp(
            config=config, open_store=lambda: DatabaseStore(database), keys=operator, **common
        )
    operator.station = app
    try:
        return app.serve()
    finally:
        operator.close()


def measure(slots: int, cycles: int, capture: str, speed: float) -> dict[str, float]:
    """One row: device, operator and station time of a cycle; units per operator-hour."""
    events = Events()
    undo = instrument(events)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            cpu = time.process_time()
            records = run_station(Path(tmp), slots, cycles, capture, speed)
            cpu = time.process_time() - cpu - events.putter_cpu_s
    finally:
        undo()
    assert len(records) == slots * cycles
    assert all(r.verdict == "pass" for r in records), [r.failures for r in records]
    rate = float(DEFAULT_RATE_HZ)
    device = []
    for cycle in range(cycles):
        in_cycle = [units[cycle].pose_device_s(rate) for units in events.units.values()]
        poses = [max(unit[k] for unit in in_cycle) for k in range(POSES)]
        device.append(sum(poses) + UNIT_OUTPUT_SAMPLES / rate)
    station_cpu = cpu / len(records)
    move = MOVE_ONE_S if slots == 1 else MOVE_FIXTURE_S
    operator = slots * sum(OPERATOR.values()) + (POSES - 1) * move
    cycle_s = operator + statistics.mean(device) + slots * station_cpu
    samples = statistics.mean(p.sample_count for r in records for p in r.poses)
    return {
        "slots": slots,
        "fixed_part": cycle_s - slots * sum(OPERATOR.values()),
        "device": statistics.mean(device),
        "operator": operator,
        "cpu": station_cpu,
        "cycle": cycle_s,
        "per_hour": 3600 * slots / cycle_s,
        "eight": cycle_s * 8 / slots,
        "samples": samples,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=2)
    parser.add_argument("--speed", type=float, default=5.0, help="virtual clock (× real time)")
    parser.add_argument("--slots", type=int, nargs="+", default=[1, 2, 4, 8])
    parser.add_argument("--capture", nargs="+", default=["fixed", "adaptive"])
    args = parser.parse_args()
    print(
        f"operator: load {OPERATOR['load']:g} s, scan {OPERATOR['scan']:g} s, unload "
        f"{OPERATOR['unload']:g} s per unit; move {MOVE_ONE_S:g} s (one putter), "
        f"{MOVE_FIXTURE_S:g} s (fixture); {args.cycles} cycles per row at {args.speed:g}×"
    )
    print(
        "| capture | slots | samples/pose | device per cycle | operator per cycle "
        "| station CPU per unit | cycle | units per operator-hour | × one slot "
        "| 8 units | × one slot |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for capture in args.capture:
        one: dict[str, float] | None = None
        rows: dict[int, dict[str, float]] = {}
        for slots in args.slots:
            m = rows[slots] = measure(slots, args.cycles, capture, args.speed)
            one = one or (m if slots == 1 else None)
            gain = f"{m['per_hour'] / one['per_hour']:.2f}" if one else "—"
            eight = f"{m['eight'] / one['eight']:.2f}" if one else "—"
            print(
                f"| {capture} | {slots} | {m['samples']:.0f} | {m['device']:.1f} s "
                f"| {m['operator']:.1f} s | {m['cpu'] * 1e3:.0f} ms | {m['cycle']:.1f} s "
                f"| {m['per_hour']:.0f} | {gain} | {m['eight']:.0f} s | {eight} |",
                flush=True,
            )
        if one is not None:
            break_even(capture, one, rows)


def break_even(capture: str, one: dict[str, float], rows: dict[int, dict[str, float]]) -> None:
    """The handling per unit (load + scan + unload) at which each target is just met.

    A cycle of K slots is ``K·h + a_K`` (``a_K``: moves, device and station time); the
    targets are ``8·(h + a_1) ≥ 4·(8h + a_8)`` and ``2·(4h + a_4) ≤ 0.45·8·(h + a_1)``.
    """
    a1 = one["fixed_part"]
    handling = sum(OPERATOR.values())
    if 8 in rows:
        h = (8 * a1 - 4 * rows[8]["fixed_part"]) / 24
        print(
            f"{capture}: 8 slots give 4× one slot while handling per unit ≤ {h:.1f} s "
            f"(assumed {handling:g} s)"
        )
    if 4 in rows:
        h = (3.6 * a1 - 2 * rows[4]["fixed_part"]) / 4.4
        print(
            f"{capture}: 4 slots do 8 units in ≤ 0.45× one slot's time while handling per "
            f"unit ≤ {h:.1f} s (assumed {handling:g} s)"
        )


if __name__ == "__main__":
    main()
