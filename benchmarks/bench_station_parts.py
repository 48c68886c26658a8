"""Where the station's CPU per unit goes at one slot: each part's thread CPU, per unit.

    python benchmarks/bench_station_parts.py              # 8 units at 1×, about 4 minutes
    python benchmarks/bench_station_parts.py --units 12
    python benchmarks/bench_station_parts.py --tick-s 1   # a pass a second

Runs the one-port station on virtual units at real speed, as ``bench_station_cpu.py``
does, with each part below wrapped to add up its ``time.thread_time`` (the outermost
call in each thread only, where a part calls itself). The sums start when the fourth
unit is plugged in, as the station's figure at work does (the first units carry the
station's start and the store's first statements). The wrappers add a little to every
part. Prints a Markdown table, dearest first.
"""

import argparse
import functools
import importlib
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

from bench_station_cpu import FIRST_AT_WORK, add_tick_option
from bench_throughput import run_station

from station.simulator.putter import VirtualPutter

#: (module, class or None for a function, name): the parts timed.
PARTS = (
    ("station.loop.app", "StationApp", "tick"),
    ("station.run.unit_run", "UnitRun", "step"),
    ("station.run.capture", "PoseCapture", "poll"),
    ("station.run.acquisition", "PoseAcquisition", "poll"),
    ("station.device.link", "PutterLink", "read_now"),
    ("station.device.link", "PutterLink", "_received"),
    ("station.device.link", "PutterLink", "data_received"),
    ("station.device.protocol", "FrameParser", "feed"),
    ("station.device.protocol", None, "decode_samples"),
    ("station.device.link", "PutterLink", "_store"),
    ("station.device.sequence", "SequenceTracker", "unwrap"),
    ("serial.serialposix", "Serial", "read"),
    ("station.run.capture", "PoseCapture", "_update_live"),
    ("station.run.capture", "PoseCapture", "_judge_live"),
    ("station.domain.signals.stillness", None, "judge_window"),
    ("station.domain.signals.samples", "SampleBlock", "summary"),
    ("station.domain.signals.samples", "SampleBlock", "concat"),
    ("station.domain.signals.orientation", None, "sense"),
    ("station.domain.signals.orientation", "Sensed", "matches"),
    ("station.run.acquisition", "StillnessDetector", "feed"),
    ("station.run.unit_run", "UnitRun", "_accept"),
    ("station.run.unit_run", "UnitRun", "_step_unit_output"),
    ("station.run.unit_run", "UnitRun", "_finish"),
    ("station.loop.demo", "ScriptedOperator", "read"),
    # The store's two threads: a run stored (and the outbox synced), a unit looked up.
    ("station.loop.results_link", "StoreWorker", "_run"),
)
#: Modules that import the timed functions by name: they get the timed one too.
IMPORTERS = (
    "station.device.link",
    "station.run.acquisition",
    "station.run.capture",
    "station.domain.signals.stillness",
)


class Nesting(threading.local):
    """How deep each part is in this thread's calls (the store's and the reader's threads
    run beside the loop's)."""

    def __init__(self) -> None:
        self.depth: Counter[str] = Counter()


class Parts:
    """Thread CPU and calls of each part, while :attr:`on`, summed over the threads."""

    def __init__(self) -> None:
        self.on = False
        self.cpu_s: Counter[str] = Counter()
        self.calls: Counter[str] = Counter()
        self._nesting = Nesting()
        #: The sums are added to from several threads (the parse runs in the loop's and
        #: the reader's, the store's work in two).
        self._sums = threading.Lock()

    def timed(self, label: str, work: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(work)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            if not self.on:
                return work(*args, **kwargs)
            depth = self._nesting.depth
            depth[label] += 1
            start = time.thread_time()
            try:
                return work(*args, **kwargs)
            finally:
                depth[label] -= 1
                if not depth[label]:
                    spent = time.thread_time() - start
                    with self._sums:
                        self.cpu_s[label] += spent
                        self.calls[label] += 1

        return wrapper


def instrument(parts: Parts) -> None:
    """Wrap every part of :data:`PARTS` (for the rest of the process)."""
    for module_name, owner_name, name in PARTS:
        module = importlib.import_module(module_name)
        owner = getattr(module, owner_name) if owner_name else module
        label = f"{owner_name}.{name}" if owner_name else name
        wrapped = parts.timed(label, getattr(owner, name))
        setattr(owner, name, wrapped)
        if owner_name is None:
            for importer in map(importlib.import_module, IMPORTERS):
                if getattr(importer, name, None) is not None:
                    setattr(importer, name, wrapped)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=8, help=f"more than {FIRST_AT_WORK - 1}")
    add_tick_option(parser)
    args = parser.parse_args()
    if args.units < FIRST_AT_WORK:
        parser.error(f"--units: at least {FIRST_AT_WORK}")
    parts = Parts()
    instrument(parts)
    serve_pty = VirtualPutter.serve_pty
    plugged = [0]

    def serve(self: VirtualPutter, alias: Any = None) -> str:
        plugged[0] += 1
        parts.on = parts.on or plugged[0] == FIRST_AT_WORK
        return serve_pty(self, alias)

    VirtualPutter.serve_pty = serve  # type: ignore[method-assign]
    with tempfile.TemporaryDirectory() as tmp:
        records = run_station(
            Path(tmp), 1, args.units, "fixed", 1.0, ahead=False, tick_s=args.tick_s
        )
    parts.on = False
    assert all(r.verdict == "pass" for r in records), [r.failures for r in records]
    at_work = args.units - FIRST_AT_WORK + 1
    print(
        f"one slot at 1×, a pass every {args.tick_s:g} s, "
        f"per unit of the {at_work} from the {FIRST_AT_WORK}th on"
    )
    print("| part | CPU a unit | calls a unit |\n|---|---|---|")
    for label, cpu_s in parts.cpu_s.most_common():
        calls = parts.calls[label] / at_work
        print(f"| `{label}` | {cpu_s * 1e3 / at_work:.1f} ms | {calls:.1f} |")


if __name__ == "__main__":
    main()
