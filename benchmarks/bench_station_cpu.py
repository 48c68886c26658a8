"""The station's CPU per unit at real speed against its floor: parse, judge, solve.

    python benchmarks/bench_station_cpu.py                 # 1 and 8 slots, three cycles at 1×
    python benchmarks/bench_station_cpu.py --slots 1 --speed 2

The **floor** is the work that follows the samples and nothing else, each part timed
alone on this machine (best of several repeats): parsing every frame the unit streamed
(its last captured sample's sequence number plus the unit-output check's 256 samples)
through the station's own link in 4 KiB chunks, judging one 1,024-sample window per
pose, and the solve. The **station** figure is what ``bench_throughput.py`` measures: the
process's CPU while the real station serves the units at 1× (the one-port station for
one slot, the fixture for several), minus the virtual putters' own threads, per unit.
Everything else the station does (the live view, journal, outbox, database) is in the
station figure and not in the floor; the issue's target is a ratio of 5 or less.

Each row runs three cycles of units (``--cycles``). The first carries the station's
start (its SQLite database created by the migrations, the roll-ups built, statements
compiled for the first time), the second still compiles the store's statements for a
run added to existing roll-ups; the last is the station at work. Each is timed from
the moment its first unit is plugged in, and the last one's figure is compared with the
floor.
"""

import argparse
import statistics
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bench_throughput import POSES, Events, instrument, run_station

from station.device.link import PutterLink
from station.device.protocol import encode_sample
from station.domain.calibration.solve import solve
from station.domain.records import RunRecord
from station.domain.run_settings import RunSettings
from station.domain.stillness import judge_window
from station.run.unit_output import UNIT_OUTPUT_SAMPLES
from station.simulator.putter import VirtualPutter

#: Frames parsed to time the parser (a minute and a half of stream).
PARSE_FRAMES = 51_200
WINDOW = 1024
CHUNK_BYTES = 4096


def best_of(repeats: int, work: Callable[[], object]) -> float:
    """The least CPU seconds ``work`` took over ``repeats`` runs."""
    times = []
    for _ in range(repeats):
        start = time.process_time()
        work()
        times.append(time.process_time() - start)
    return min(times)


def parse_cost_per_frame() -> float:
    """CPU seconds to parse one sample frame through :class:`PutterLink` in big chunks."""
    frames = b"".join(
        encode_sample(i, (2048, 2048, 2867), (0, 0, 0), 2500) for i in range(PARSE_FRAMES)
    )

    def parse() -> None:
        link = PutterLink("floor", PARSE_FRAMES)
        for at in range(0, len(frames), CHUNK_BYTES):
            link.data_received(frames[at : at + CHUNK_BYTES])

    return best_of(5, parse) / PARSE_FRAMES


def judge_and_solve_cost(record: RunRecord) -> float:
    """CPU seconds to judge one window per pose and solve, on a stored unit's poses."""
    link = PutterLink("floor", POSES * WINDOW)
    link.data_received(
        b"".join(
            encode_sample(i, (2048, 2048, 2867), (1, 0, 0), 2500) for i in range(POSES * WINDOW)
        )
    )
    block = link.raw.drain()
    windows = [block[k * WINDOW : (k + 1) * WINDOW] for k in range(POSES)]
    stillness = RunSettings().stillness
    means = [p.mean.as_tuple() for p in record.poses if p.role == "fit"]

    def work() -> None:
        for window in windows:
            judge_window(window, stillness)
        solve(means)

    return best_of(20, work)


def putter_cpu_s(putter: VirtualPutter) -> float:
    """CPU seconds a virtual putter's thread has used so far (0 once it has ended)."""
    thread = putter._thread
    if thread is None or thread.ident is None or not thread.is_alive():
        return 0.0
    return time.clock_gettime(time.pthread_getcpuclockid(thread.ident))


def measure(slots: int, speed: float, cycles: int) -> dict[str, float]:
    """``cycles`` cycles of ``slots`` units at ``speed``: floor and station CPU per unit.

    Each cycle is timed from the moment its first unit is plugged in (the first from the
    station's start, the last to the station's end), the virtual putters' CPU in it
    taken off.
    """
    events = Events()
    undo = instrument(events)
    serve_pty, close = VirtualPutter.serve_pty, VirtualPutter.close
    live: set[VirtualPutter] = set()
    #: Process CPU less the putters' CPU so far, at the start of each cycle.
    marks: list[float] = []

    def station_cpu() -> float:
        putters = events.putter_cpu_s + sum(map(putter_cpu_s, live))
        return time.process_time() - putters

    def serve(self: VirtualPutter, alias: Any = None) -> str:
        if sum(map(len, events.units.values())) == len(marks) * slots:
            marks.append(station_cpu())
        live.add(self)
        return serve_pty(self, alias)

    def closed(self: VirtualPutter) -> None:
        live.discard(self)
        close(self)

    VirtualPutter.serve_pty = serve  # type: ignore[method-assign]
    VirtualPutter.close = closed  # type: ignore[method-assign]
    try:
        with tempfile.TemporaryDirectory() as tmp:
            start = station_cpu()
            records = run_station(Path(tmp), slots, cycles, "fixed", speed, ahead=False)
            marks.append(station_cpu())
    finally:
        VirtualPutter.serve_pty, VirtualPutter.close = serve_pty, close  # type: ignore[method-assign]
        undo()
    assert len(records) == cycles * slots
    assert all(r.verdict == "pass" for r in records), [r.failures for r in records]
    assert len(marks) == cycles + 1, marks
    marks[0] = start
    first_cycle = (marks[1] - marks[0]) / slots
    last_cycle = (marks[-1] - marks[-2]) / slots
    frames = statistics.mean(
        unit.captures[-1] + 1 + UNIT_OUTPUT_SAMPLES
        for units in events.units.values()
        for unit in units
    )
    parse = parse_cost_per_frame() * frames
    judge_solve = judge_and_solve_cost(records[0])
    floor = parse + judge_solve
    return {
        "frames": frames,
        "parse": parse,
        "judge_solve": judge_solve,
        "floor": floor,
        "first": first_cycle,
        "station": last_cycle,
        "ratio": last_cycle / floor,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slots", type=int, nargs="+", default=[1, 8])
    parser.add_argument("--speed", type=float, default=1.0, help="virtual clock (× real time)")
    parser.add_argument("--cycles", type=int, default=3, help="cycles per row (at least 2)")
    args = parser.parse_args()
    if args.cycles < 2:
        parser.error("--cycles: at least 2 (the first carries the station's start)")
    print(f"station CPU per unit at {args.speed:g}×, {args.cycles} cycles per row")
    print(
        "| slots | frames per unit | parse | judge + solve | floor "
        "| station, first cycle | station, last cycle | × floor |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for slots in args.slots:
        m = measure(slots, args.speed, args.cycles)
        print(
            f"| {slots} | {m['frames']:.0f} | {m['parse'] * 1e3:.1f} ms "
            f"| {m['judge_solve'] * 1e3:.1f} ms | {m['floor'] * 1e3:.1f} ms "
            f"| {m['first'] * 1e3:.0f} ms | {m['station'] * 1e3:.0f} ms | {m['ratio']:.1f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
