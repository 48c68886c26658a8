"""Units per operator-hour for 1, 2, 4 and 8 slots, fixed and adaptive capture.

    python benchmarks/bench_throughput.py                 # 2 cycles per row, at 5×
    python benchmarks/bench_throughput.py --cycles 1      # quicker
    python benchmarks/bench_throughput.py --speed 1 --slots 8 --capture fixed --cycles 1

A plant buys a station on units per operator-hour. Each row runs the real station on
virtual putters over real ptys: the one-port station (:class:`station.loop.app.StationApp`
with the demo's scripted operator) for one slot, the fixture
(:class:`station.loop.fixture.app.FixtureApp` with
:class:`station.loop.fixture.demo.FixtureOperator`, each unit with its own mounting
misalignment) for several, storing into SQLite.

**Device time** is read from the units' own sequence numbers, so it does not depend on
the virtual speed or on this machine: for each pose and unit, from the end of the move
into the pose (the move's first sample plus its duration) to the last sample of the
accepted window; for the first pose, from the unit's stream start (its scan) to its
window's last sample. A fixture's pose lasts as long as its slowest slot; then each
unit checks its own output (256 calibrated samples, 0.51 s, in parallel).

**Operator time** is added as stated below (``OPERATOR``), not simulated: loading,
scanning and unloading each unit, and the moves between the seven poses (six moves).
**Scanning ahead** (:class:`station.loop.fixture.ahead.ScanAhead`), the operator scans one
label of the next cycle's units in each pose while the fixture captures, and presses
Enter once each such unit is in its slot: a pose then lasts as long as its slowest slot
or its scan, whichever is longer, and those units cost a confirm instead of a scan. The
station is run that way (the fixture's demo operator scans ahead, and the next cycle's
units are taken from the queue); the figures are for a cycle in steady state, where
``min(K, 7)`` of its K units were scanned ahead during the cycle before.

**Station time**: the station's CPU per unit (process CPU minus the virtual putters'
threads and the scripted operator's calls, which stand in for the units and the person),
counted once per unit in the cycle as if nothing of it overlapped.

    cycle = K × (load + unload) + (K − A) × scan + A × confirm + 6 × move(K)
            + Σ_pose max(max_slot(device), scan if a label is scanned in it) + 0.51 s
            + K × station CPU per unit          (A = min(K, 7) scanning ahead, else 0)
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

from station.device import DEFAULT_RATE_HZ
from station.domain.product.limits import load_profile
from station.domain.product.run_settings import RunSettings
from station.loop.app import StationApp
from station.loop.config import StationConfig
from station.loop.demo import MOVE_S, ScriptedOperator
from station.loop.fixture.ahead import ScanAhead
from station.loop.fixture.app import FixtureApp
from station.loop.fixture.demo import FixtureOperator
from station.loop.live_loop import TICK_S
from station.results.storage import DatabaseStore
from station.run.acquisition import PoseResult
from station.run.unit_output import UNIT_OUTPUT_SAMPLES
from station.run.unit_run import UnitRun
from station.simulator.putter import VirtualPutter

#: Stated operator times, seconds (see docs/benchmarks.md, "throughput", for where from).
OPERATOR = {
    "load": 2.0,  # take the unit from the tray, seat it, plug its cable
    "scan": 1.5,  # aim the hand scanner at the label, beep
    "unload": 1.5,  # unplug, put it where the screen says
    "confirm": 0.3,  # press Enter once the unit scanned ahead is in its slot
}
#: Per unit handled in the cycle: load and unload (and its scan, or a confirm).
HANDLING = OPERATOR["load"] + OPERATOR["unload"]


def handling(ahead: bool) -> float:
    """The operator's seconds per unit in the cycle, poses aside."""
    return HANDLING + OPERATOR["confirm" if ahead else "scan"]


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
    """Units by port, in the order they were plugged in; CPU of the putters' threads and
    of the scripted operator."""

    units: dict[str, list[Unit]] = field(default_factory=lambda: defaultdict(list))
    putter_cpu_s: float = 0.0
    #: The scripted operator's CPU (its keys, the putters it plugs in and moves): the
    #: person at the station and the units, run in the station's thread, not its work.
    operator_cpu_s: float = 0.0
    #: The main thread's CPU clock when the operator's call in progress began.
    operator_since: float | None = None
    #: Units the next cycle's scan took from the labels scanned ahead.
    taken_ahead: int = 0

    def operator_cpu(self) -> float:
        """The operator's CPU so far, its call in progress (in this thread) included."""
        if self.operator_since is None:
            return self.operator_cpu_s
        return self.operator_cpu_s + time.thread_time() - self.operator_since


#: The demo's scripted operators: their CPU is the person's and the units', not the station's.
OPERATORS = (ScriptedOperator, FixtureOperator)


def instrument(events: Events) -> Callable[[], None]:
    """Note plug-ins, moves, accepted captures and the putters' and the operator's CPU;
    returns the undo."""
    serve_pty = VirtualPutter.serve_pty
    move_to = VirtualPutter.move_to
    close = VirtualPutter.close
    accept = UnitRun._accept
    take = ScanAhead.take
    #: The operators' methods, kept to be restored: reading keys, and the last unplugs.
    operating = [(cls, name, getattr(cls, name)) for cls in OPERATORS for name in ("read", "close")]

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

    def operated(method: Callable[[Any], Any]) -> Callable[[Any], Any]:
        def timed(self: Any) -> Any:
            events.operator_since = time.thread_time()
            try:
                return method(self)
            finally:
                events.operator_cpu_s += time.thread_time() - events.operator_since
                events.operator_since = None

        return timed

    def taken(self: ScanAhead, slot: Any) -> str | None:
        serial = take(self, slot)
        events.taken_ahead += serial is not None
        return serial

    VirtualPutter.serve_pty = serve  # type: ignore[method-assign]
    VirtualPutter.move_to = move  # type: ignore[method-assign]
    VirtualPutter.close = closed  # type: ignore[method-assign]
    UnitRun._accept = accepted  # type: ignore[method-assign]
    ScanAhead.take = taken  # type: ignore[method-assign]
    for cls, name, method in operating:
        setattr(cls, name, operated(method))

    def undo() -> None:
        VirtualPutter.serve_pty = serve_pty  # type: ignore[method-assign]
        VirtualPutter.move_to = move_to  # type: ignore[method-assign]
        VirtualPutter.close = close  # type: ignore[method-assign]
        UnitRun._accept = accept  # type: ignore[method-assign]
        ScanAhead.take = take  # type: ignore[method-assign]
        for cls, name, method in operating:
            setattr(cls, name, method)

    return undo


def run_station(
    data: Path,
    slots: int,
    cycles: int,
    capture: str,
    speed: float,
    ahead: bool,
    tick_s: float = TICK_S,
) -> list[Any]:
    """The station on ``slots × cycles`` virtual units, a pass every ``tick_s``; their
    records.

    One slot scanning at load is today's one-port station; anything else the fixture.
    """
    units = slots * cycles
    database = f"sqlite:///{data}/results.sqlite3"
    run = RunSettings(capture=capture)  # type: ignore[arg-type]
    common: dict[str, Any] = {
        "profile": load_profile(),
        "console": Console(quiet=True),
        "units": units,
        "tick_s": tick_s,
    }
    operator: ScriptedOperator | FixtureOperator
    app: StationApp | FixtureApp
    if slots == 1 and not ahead:
        port = data / "putter"
        config = StationConfig(data_dir=data, port=str(port), database_url=database, run=run)
        operator = ScriptedOperator(units=units, port=port, seed=11, speed=speed)
        app = StationApp(
            config=config,
            open_store=lambda: DatabaseStore(database),
            keys=operator,
            probe_ports=False,
            **common,
        )
    else:
        ports = [data / f"putter-slot{n}" for n in range(1, slots + 1)]
        config = StationConfig(
            data_dir=data, slots=tuple(map(str, ports)), database_url=database, run=run
        )
        operator = FixtureOperator(units=units, ports=ports, seed=11, speed=speed, scan_ahead=ahead)
        app = FixtureApp(
            config=config, open_store=lambda: DatabaseStore(database), keys=operator, **common
        )
    operator.station = app
    try:
        return app.serve()
    finally:
        operator.close()


def measure(slots: int, cycles: int, capture: str, speed: float, ahead: bool) -> dict[str, float]:
    """One row: device, operator and station time of a cycle; units per operator-hour."""
    events = Events()
    undo = instrument(events)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            cpu = time.process_time()
            records = run_station(Path(tmp), slots, cycles, capture, speed, ahead)
            cpu = time.process_time() - cpu - events.putter_cpu_s - events.operator_cpu()
    finally:
        undo()
    assert len(records) == slots * cycles
    assert all(r.verdict == "pass" for r in records), [r.failures for r in records]
    scanned_ahead = min(slots, POSES) if ahead else 0
    # The station really took the next cycle's units from the labels scanned ahead.
    assert events.taken_ahead == scanned_ahead * (cycles - 1), events.taken_ahead
    rate = float(DEFAULT_RATE_HZ)
    device, poses_s = [], []
    for cycle in range(cycles):
        in_cycle = [units[cycle].pose_device_s(rate) for units in events.units.values()]
        poses = [max(unit[k] for unit in in_cycle) for k in range(POSES)]
        device.append(sum(poses) + UNIT_OUTPUT_SAMPLES / rate)
        scans = [OPERATOR["scan"] if k < scanned_ahead else 0.0 for k in range(POSES)]
        poses_s.append(sum(map(max, poses, scans)) + UNIT_OUTPUT_SAMPLES / rate)
    station_cpu = cpu / len(records)
    move = MOVE_ONE_S if slots == 1 else MOVE_FIXTURE_S
    operator = (
        slots * HANDLING
        + (slots - scanned_ahead) * OPERATOR["scan"]
        + scanned_ahead * OPERATOR["confirm"]
        + (POSES - 1) * move
    )
    cycle_s = operator + statistics.mean(poses_s) + slots * station_cpu
    samples = statistics.mean(p.sample_count for r in records for p in r.poses)
    return {
        "slots": slots,
        "fixed_part": cycle_s - slots * handling(ahead),
        "handling": handling(ahead),
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
    parser.add_argument(
        "--scanning", nargs="+", default=["at load", "ahead"], choices=["at load", "ahead"]
    )
    args = parser.parse_args()
    times = ", ".join(f"{name} {seconds:g} s" for name, seconds in OPERATOR.items())
    print(
        f"operator: {times} per unit; move {MOVE_ONE_S:g} s (one putter), "
        f"{MOVE_FIXTURE_S:g} s (fixture); {args.cycles} cycles per row at {args.speed:g}×"
    )
    print(
        "| capture | scanning | slots | samples/pose | device per cycle | operator per cycle "
        "| station CPU per unit | cycle | units per operator-hour | × one slot | × today "
        "| 8 units | × one slot | × today |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for capture in args.capture:
        today: dict[str, float] | None = None
        for scanning in args.scanning:
            ahead = scanning == "ahead"
            one: dict[str, float] | None = None
            rows: dict[int, dict[str, float]] = {}
            for slots in args.slots:
                m = rows[slots] = measure(slots, args.cycles, capture, args.speed, ahead)
                one = one or (m if slots == 1 else None)
                today = today or (m if slots == 1 and not ahead else None)
                print(
                    f"| {capture} | {scanning} | {slots} | {m['samples']:.0f} "
                    f"| {m['device']:.1f} s | {m['operator']:.1f} s | {m['cpu'] * 1e3:.0f} ms "
                    f"| {m['cycle']:.1f} s | {m['per_hour']:.0f} "
                    f"| {ratio(m, one, 'per_hour')} | {ratio(m, today, 'per_hour')} "
                    f"| {m['eight']:.0f} s | {ratio(m, one, 'eight')} "
                    f"| {ratio(m, today, 'eight')} |",
                    flush=True,
                )
            if one is not None:
                break_even(f"{capture}, scanning {scanning}", one, rows)


def ratio(row: dict[str, float], base: dict[str, float] | None, key: str) -> str:
    """``row[key]`` over the same figure of ``base`` (— without one)."""
    return f"{row[key] / base[key]:.2f}" if base is not None else "—"


def break_even(label: str, one: dict[str, float], rows: dict[int, dict[str, float]]) -> None:
    """The handling per unit at which each target is just met.

    A cycle of K slots is ``K·h + a_K`` (``h``: the operator's seconds per unit in the
    cycle, poses aside; ``a_K``: the rest); the targets are ``8·(h + a_1) ≥ 4·(8h + a_8)``
    and ``2·(4h + a_4) ≤ 0.45·8·(h + a_1)``.
    """
    a1, assumed = one["fixed_part"], one["handling"]
    targets: list[tuple[str, float]] = []
    if 8 in rows:
        h = (8 * a1 - 4 * rows[8]["fixed_part"]) / 24
        targets.append(("8 slots give 4× one slot", h))
    if 4 in rows:
        h = (3.6 * a1 - 2 * rows[4]["fixed_part"]) / 4.4
        targets.append(("4 slots do 8 units in ≤ 0.45× one slot's time", h))
    for target, h in targets:
        reach = f"while handling per unit ≤ {h:.1f} s" if h > 0 else "not even with no handling"
        print(f"{label}: {target} {reach} (assumed {assumed:g} s)")


if __name__ == "__main__":
    main()
