"""The station's CPU per unit at real speed against its floor: parse, judge, solve.

    python benchmarks/bench_station_cpu.py                 # 1 and 8 slots, six cycles at 1×
    python benchmarks/bench_station_cpu.py --slots 1 --speed 2
    python benchmarks/bench_station_cpu.py --slots 1 --tick-s 0.5   # two passes a second

The **floor** is the work that follows the samples and nothing else, each part timed
alone on this machine (best of several repeats): parsing every frame the unit streamed
(its last captured sample's sequence number plus the unit-output check's 256 samples)
through the station's own link in 4 KiB chunks, judging one 1,024-sample window per
pose, and the solve. The **station** figure is what ``bench_throughput.py`` measures: the
process's CPU while the real station serves the units at 1× (the one-port station for
one slot, the fixture for several), minus the virtual putters' own threads and the
scripted operator's calls (its keys, and the putters it plugs in and moves: the person
at the station and the units, run in the station's thread), per unit.
Everything else the station does (the live view, journal, outbox, database) is in the
station figure and not in the floor; the issue's target is a ratio of 5 or less.

Each row runs six cycles of units (``--cycles``), each timed from the moment its first
unit is plugged in. The first carries the station's start (its SQLite database created
by the migrations, the roll-ups built, statements compiled for the first time). A run
is stored beside the loop, a moment after its verdict: often once the next unit is
plugged in, never later than the unit after it. The first run added to existing
roll-ups (the second run of one slot, a first cycle's second of several) compiles the
store's statements for that (some 200 ms on a busy machine, against 12–25 ms for a run
stored warm), and it has landed by the start of the fourth cycle. So the **station at
work** is the CPU from the fourth cycle's start to the end, per unit of those cycles:
every run stored in it is stored warm, and all but at most one cycle's runs are its
own. (An earlier figure, the last cycle alone, held the compiling store whenever the
second run of one slot landed late.) That figure is compared with the floor.

Beside it, **the floor's work alone at the station's pace** (:func:`paced_floor_cost`):
the same work spread over the passes the station makes, four a second (``--tick-s``),
each after a rest, nothing else in the process. A piece of work woken after a quarter
second's rest takes several times its CPU in a tight loop on a virtual machine (its
caches have gone cold), and at one slot every pass pays that for one unit. It is not a
floor: in the station the same parse costs less than this, the pass's other work and the
virtual putters' threads keeping the caches warmer. It shows what the wakes weigh.
"""

import argparse
import contextlib
import math
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
from station.domain.constants import DEFAULT_RATE_HZ
from station.domain.product.run_settings import RunSettings
from station.domain.record.records import RunRecord
from station.domain.signals.samples import SampleBlock
from station.domain.signals.stillness import judge_window
from station.loop.live_loop import TICK_S
from station.run.unit_output import UNIT_OUTPUT_SAMPLES
from station.simulator.putter import VirtualPutter

#: The first cycle at work: the cycles before it hold the station's start and the
#: store's first statements of a run added to existing roll-ups (see the module).
FIRST_AT_WORK = 4
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


def still_stream(count: int, gyro: tuple[int, int, int] = (0, 0, 0)) -> bytes:
    """``count`` sample frames of a putter lying face up and still, numbered from 0."""
    return b"".join(encode_sample(i, (2048, 2048, 2867), gyro, 2500) for i in range(count))


def parse_cost_per_frame() -> float:
    """CPU seconds to parse one sample frame through :class:`PutterLink` in big chunks."""
    frames = still_stream(PARSE_FRAMES)

    def parse() -> None:
        link = PutterLink("floor", PARSE_FRAMES)
        for at in range(0, len(frames), CHUNK_BYTES):
            link.data_received(frames[at : at + CHUNK_BYTES])

    return best_of(5, parse) / PARSE_FRAMES


def pose_windows() -> list[SampleBlock]:
    """One still 1,024-sample window per pose, as the link stores them."""
    link = PutterLink("floor", POSES * WINDOW)
    link.data_received(still_stream(POSES * WINDOW, gyro=(1, 0, 0)))
    block = link.raw.drain()
    return [block[k * WINDOW : (k + 1) * WINDOW] for k in range(POSES)]


def judge_and_solve_cost(record: RunRecord) -> float:
    """CPU seconds to judge one window per pose and solve, on a stored unit's poses."""
    windows = pose_windows()
    stillness = RunSettings().stillness
    means = [p.mean.as_tuple() for p in record.poses if p.role == "fit"]

    def work() -> None:
        for window in windows:
            judge_window(window, stillness)
        solve(means)

    return best_of(20, work)


def paced_floor_cost(
    frames: float, record: RunRecord, speed: float, slots: int, tick_s: float
) -> float:
    """CPU seconds per unit of the floor's work done alone at the station's pace: each of
    ``slots`` units' ``frames`` parsed through its own link in as many pieces as the loop
    makes passes over a unit (a pass every ``tick_s`` while the putters stream at
    ``speed``), every slot's piece in each pass after the rest between two passes, one
    window per pose judged in the passes where the poses end and the solve in the last;
    the thread's CPU in the passes alone.

    The same work as the floor (:func:`parse_cost_per_frame`,
    :func:`judge_and_solve_cost`), spread as the station must spread it to show the
    operator the samples every ``tick_s`` (four times a second at the station's pace):
    each pass starts on caches the rest let go cold (see the module). Takes about one
    unit's time at ``speed`` of wall clock.
    """
    passes = max(POSES, round(frames / (DEFAULT_RATE_HZ * speed * tick_s)))
    count = round(frames)
    data = still_stream(count)
    size = len(data) // count
    links = [PutterLink(f"floor{k}", count) for k in range(slots)]
    stillness = RunSettings().stillness
    means = [p.mean.as_tuple() for p in record.poses if p.role == "fit"]
    # The pass in which each pose's window ends: the poses follow one another evenly.
    judged = {round((k + 1) * passes / POSES) - 1: w for k, w in enumerate(pose_windows())}
    cpu = 0.0
    due = time.monotonic()
    with contextlib.ExitStack() as attended:
        for link in links:  # each link parses its piece and returns, never resting
            attended.enter_context(link.attended())
        for n in range(passes):
            due += tick_s
            time.sleep(max(0.0, due - time.monotonic()))
            piece = data[n * count // passes * size : (n + 1) * count // passes * size]
            start = time.thread_time()
            for link in links:
                link.data_received(piece)
                if (window := judged.get(n)) is not None:
                    judge_window(window, stillness)
                if n == passes - 1:
                    solve(means)
            cpu += time.thread_time() - start
    return cpu / slots


def seconds_between_passes(text: str) -> float:
    """``--tick-s``: a positive, finite number of seconds."""
    try:
        seconds = float(text)
    except ValueError:
        seconds = math.nan
    if not 0 < seconds < math.inf:
        raise argparse.ArgumentTypeError(f"seconds, more than 0, got {text!r}")
    return seconds


def add_tick_option(parser: argparse.ArgumentParser) -> None:
    """``--tick-s``: the wall-clock seconds between the station's passes (this script's and
    ``bench_station_parts.py``'s)."""
    parser.add_argument(
        "--tick-s",
        type=seconds_between_passes,
        default=TICK_S,
        help=f"wall-clock seconds between the loop's passes, whatever the speed (the "
        f"station's: {TICK_S:g})",
    )


def putter_cpu_s(putter: VirtualPutter) -> float:
    """CPU seconds a virtual putter's thread has used so far (0 once it has ended)."""
    thread = putter._thread
    if thread is None or thread.ident is None or not thread.is_alive():
        return 0.0
    return time.clock_gettime(time.pthread_getcpuclockid(thread.ident))


def measure(slots: int, speed: float, cycles: int, tick_s: float) -> dict[str, float]:
    """``cycles`` cycles of ``slots`` units at ``speed``, a pass every ``tick_s``: floor
    and station CPU per unit.

    Each cycle is timed from the moment its first unit is plugged in (the first from the
    station's start, the last to the station's end), the virtual putters' and the
    operator's CPU in it taken off.
    """
    events = Events()
    undo = instrument(events)
    serve_pty, close = VirtualPutter.serve_pty, VirtualPutter.close
    live: set[VirtualPutter] = set()
    #: Process CPU less the putters' and the operator's CPU so far, at each cycle's start.
    marks: list[float] = []

    def station_cpu() -> float:
        putters = events.putter_cpu_s + sum(map(putter_cpu_s, live))
        # A cycle starts inside the operator's call (it plugs the unit in).
        return time.process_time() - putters - events.operator_cpu()

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
            records = run_station(
                Path(tmp), slots, cycles, "fixed", speed, ahead=False, tick_s=tick_s
            )
            marks.append(station_cpu())
    finally:
        VirtualPutter.serve_pty, VirtualPutter.close = serve_pty, close  # type: ignore[method-assign]
        undo()
    assert len(records) == cycles * slots
    assert all(r.verdict == "pass" for r in records), [r.failures for r in records]
    assert len(marks) == cycles + 1, marks
    marks[0] = start
    first_cycle = (marks[1] - marks[0]) / slots
    at_work = (marks[-1] - marks[FIRST_AT_WORK - 1]) / ((cycles - FIRST_AT_WORK + 1) * slots)
    frames = statistics.mean(
        unit.captures[-1] + 1 + UNIT_OUTPUT_SAMPLES
        for units in events.units.values()
        for unit in units
    )
    parse = parse_cost_per_frame() * frames
    judge_solve = judge_and_solve_cost(records[0])
    floor = parse + judge_solve
    paced = paced_floor_cost(frames, records[0], speed, slots, tick_s)
    return {
        "frames": frames,
        "parse": parse,
        "judge_solve": judge_solve,
        "floor": floor,
        "first": first_cycle,
        "station": at_work,
        "ratio": at_work / floor,
        "paced": paced,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--slots", type=int, nargs="+", default=[1, 8])
    parser.add_argument("--speed", type=float, default=1.0, help="virtual clock (× real time)")
    parser.add_argument(
        "--cycles", type=int, default=6, help=f"cycles per row (at least {FIRST_AT_WORK})"
    )
    add_tick_option(parser)
    args = parser.parse_args()
    if args.cycles < FIRST_AT_WORK:
        parser.error(
            f"--cycles: at least {FIRST_AT_WORK} (the cycles before the "
            f"{FIRST_AT_WORK}th carry the station's start)"
        )
    print(
        f"station CPU per unit at {args.speed:g}×, {args.cycles} cycles per row, "
        f"a pass every {args.tick_s:g} s"
    )
    print(
        "| slots | frames per unit | parse | judge + solve | floor "
        "| station, first cycle | station at work | × floor "
        "| the floor's work alone at the station's pace |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for slots in args.slots:
        m = measure(slots, args.speed, args.cycles, args.tick_s)
        print(
            f"| {slots} | {m['frames']:.0f} | {m['parse'] * 1e3:.1f} ms "
            f"| {m['judge_solve'] * 1e3:.1f} ms | {m['floor'] * 1e3:.1f} ms "
            f"| {m['first'] * 1e3:.0f} ms | {m['station'] * 1e3:.0f} ms | {m['ratio']:.1f} "
            f"| {m['paced'] * 1e3:.1f} ms |",
            flush=True,
        )


if __name__ == "__main__":
    main()
