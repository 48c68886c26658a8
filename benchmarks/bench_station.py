"""The station's own overhead per unit, beyond the time its samples take to arrive.

    python benchmarks/bench_station.py            # 3 units at 10× and 1 unit in real time
    python benchmarks/bench_station.py --quick    # 2 units at 10× only
    python benchmarks/bench_station.py --cycle    # one unit per profile at 1×: the cycle

A still window cannot be judged before its last sample has arrived, nor the unit's
own output before its 256 calibrated samples have. For every pose this measures the
wall time from the arrival of the accepted window's last sample (stream start plus
its sequence number over the rate) to the capture; after the verification pose, the
time to the verdict beyond the 256 calibrated samples. Their sum is everything the
station adds: window evaluations (every 32 samples), orientation checks, solving,
journal writes, write-back and read-back, the database, screens. Reported against
the physical acquisition time of the seven windows (7 × 1024 samples at 500/s).
Target: under 5 %.

``--cycle`` measures the whole cycle of one unit, from the scan to the verdict, for the
six-pose default and for the whole-unit profile (twelve poses, the verification pose
and the verification move), with fixed 1024-sample windows and the scripted operator's
1.5 s moves, at 1× (device time = wall time).
"""

import argparse
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from rich.console import Console

from station.device import DEFAULT_RATE_HZ, PutterDriver
from station.domain.product.limits import load_profile
from station.loop.app import StationApp
from station.loop.config import StationConfig
from station.loop.demo import ScriptedOperator
from station.results.storage import DatabaseStore
from station.run.acquisition import PoseAcquisition, PoseResult
from station.run.unit_output import UNIT_OUTPUT_SAMPLES

WINDOW = 1024


class Clock:
    """Wall times of the events the overhead is measured between."""

    def __init__(self) -> None:
        self.stream_started = 0.0
        self.captures: list[tuple[float, int]] = []  # (wall time, last sequence number)


def instrument(clock: Clock) -> Callable[[], None]:
    """Note stream starts and accepted windows; returns the undo."""
    original_start = PutterDriver.start_stream
    original_poll = PoseAcquisition.poll

    def start_stream(self: PutterDriver, calibrated: bool = False) -> None:
        original_start(self, calibrated)
        if not calibrated:
            clock.stream_started = time.perf_counter()

    def poll(self: PoseAcquisition) -> PoseResult | None:
        had = self.result is not None
        result = original_poll(self)
        if result is not None and not had:
            clock.captures.append((time.perf_counter() - clock.stream_started, result.last_seq))
        return result

    PutterDriver.start_stream = start_stream  # type: ignore[method-assign]
    PoseAcquisition.poll = poll  # type: ignore[method-assign]

    def undo() -> None:
        PutterDriver.start_stream = original_start  # type: ignore[method-assign]
        PoseAcquisition.poll = original_poll  # type: ignore[method-assign]

    return undo


def measure(units: int, speed: float) -> dict[str, Any]:
    clock = Clock()
    undo = instrument(clock)
    verdicts: list[float] = []
    try:
        with tempfile.TemporaryDirectory() as tmp:
            data = Path(tmp)
            port = data / "putter"
            config = StationConfig(
                data_dir=data, port=str(port), database_url=f"sqlite:///{data}/r.sqlite3"
            )
            operator = ScriptedOperator(units=units, port=port, seed=7, speed=speed)
            app = StationApp(
                config=config,
                profile=load_profile(),
                open_store=lambda: DatabaseStore(config.database_url),
                keys=operator,
                console=Console(quiet=True),
                units=units,
            )
            operator.station = app
            finish = app.lifecycle.finish

            def timed_finish(slot: Any) -> Any:
                verdicts.append(time.perf_counter() - clock.stream_started)
                return finish(slot)

            app.lifecycle.finish = timed_finish  # type: ignore[method-assign]
            try:
                records = app.serve()
            finally:
                operator.close()
    finally:
        undo()
    assert all(r.verdict == "pass" for r in records), [r.failures for r in records]
    per_sample = 1.0 / DEFAULT_RATE_HZ / speed
    pose_latency = [wall - (seq + 1) * per_sample for wall, seq in clock.captures]
    # The verdict comes after write-back, read-back and 256 calibrated samples.
    last_captures = clock.captures[6::7]
    closing = [
        v - wall - UNIT_OUTPUT_SAMPLES * per_sample
        for v, (wall, _) in zip(verdicts, last_captures, strict=True)
    ]
    overhead = (sum(pose_latency) + sum(closing)) / units
    windows = 7 * WINDOW * per_sample
    return {
        "units": units,
        "speed": speed,
        "pose": sum(pose_latency) / len(pose_latency),
        "closing": sum(closing) / units,
        "overhead": overhead,
        "share": overhead / windows,
        "windows": windows,
    }


def cycle(profile: str, capture: str = "fixed", speed: float = 1.0) -> dict[str, Any]:
    """One unit of ``profile`` (and its shipped run plan) with ``capture`` windows (fixed
    or adaptive): seconds from scan to verdict, and the seconds of its still windows."""
    marks: list[float] = []
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp)
        port = data / "putter"
        config = StationConfig(
            data_dir=data,
            port=str(port),
            database_url=f"sqlite:///{data}/r.sqlite3",
            limits_profile=profile,
            run={"capture": capture},
        )
        operator = ScriptedOperator(units=1, port=port, seed=7, speed=speed)
        app = StationApp(
            config=config,
            profile=load_profile(None, profile),
            open_store=lambda: DatabaseStore(config.database_url),
            keys=operator,
            console=Console(quiet=True),
            units=1,
        )
        operator.station = app
        start, finish = app.lifecycle.start, app.lifecycle.finish

        def timed_start(*args: Any, **kwargs: Any) -> Any:
            marks.append(time.perf_counter())
            return start(*args, **kwargs)

        def timed_finish(slot: Any) -> Any:
            marks.append(time.perf_counter())
            return finish(slot)

        app.lifecycle.start = timed_start  # type: ignore[method-assign]
        app.lifecycle.finish = timed_finish  # type: ignore[method-assign]
        try:
            (record,) = app.serve()
        finally:
            operator.close()
    assert record.verdict == "pass", record.failures
    return {
        "profile": profile,
        "capture": capture,
        "poses": len(record.poses),
        "windows": sum(p.sample_count for p in record.poses) / DEFAULT_RATE_HZ,
        "cycle": (marks[1] - marks[0]) * speed,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--cycle", action="store_true")
    args = parser.parse_args()
    if args.cycle:
        print("| profile | capture | poses captured | windows | cycle, scan → verdict (1×) |")
        print("|---|---|---|---|---|")
        for profile in ("kxm52-production", "whole-unit"):
            for capture in ("fixed", "adaptive"):
                c = cycle(profile, capture)
                print(
                    f"| {c['profile']} | {c['capture']} | {c['poses']} | {c['windows']:.1f} s "
                    f"| {c['cycle']:.1f} s |"
                )
        return
    runs = [(2, 10.0)] if args.quick else [(3, 10.0), (2, 1.0)]
    print(
        "| units | clock | 7 windows | per pose: last sample → capture | "
        "verification capture → verdict, beyond 256 samples | overhead per unit | share |"
    )
    print("|---|---|---|---|---|---|---|")
    for units, speed in runs:
        m = measure(units, speed)
        print(
            f"| {m['units']} | {m['speed']:g}× | {m['windows']:.2f} s | {m['pose'] * 1e3:.0f} ms "
            f"| {m['closing'] * 1e3:.0f} ms | {m['overhead'] * 1e3:.0f} ms | {m['share']:.1%} |"
        )


if __name__ == "__main__":
    main()
