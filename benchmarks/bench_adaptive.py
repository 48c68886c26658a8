"""Adaptive against fixed capture: samples per pose and the unit's cycle, in device time.

    python benchmarks/bench_adaptive.py            # 4 units per noise level and mode
    python benchmarks/bench_adaptive.py --quick    # 2 units each
    python benchmarks/bench_adaptive.py --speed 5  # device clock 5× real time (default 20)

Each unit is a virtual putter (its own seed) with a given accelerometer noise, run by
the station's own :class:`station.run.unit_run.UnitRun` over a real pty at ``--speed`` times
real time (default 20);
a scripted operator turns it into each pose the run asks for (1.5 s moves, with the
handling motion and put-down tremor of a person). Reported from the stored record and
the putter's clock: samples per pose (mean, min–max over the seven poses of every
unit), the seven windows' device time, and the cycle from the first move to the
verdict in device time (moves, settling, windows, write-back, the unit-output check;
not the scan or loading). Device time does not depend on this machine's speed except
for the station's polling latency (a few ms of wall time per pose, times the speed: on
a loaded machine at 20× this adds seconds to the cycle, so the cycle is measured at 5×).
"""

import argparse
import statistics
import tempfile
import time
import uuid
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from station.device import DEFAULT_RATE_HZ
from station.domain.product.limits import load_profile
from station.domain.product.run_settings import RunSettings
from station.results.journal import JournalFile, RunJournal
from station.run.phases import Phase
from station.run.unit_run import UnitRun, open_unit
from station.simulator.putter import VirtualPutter

MOVE_S = 1.5


def one_unit(
    tmp: Path, seed: int, noise: float, settings: RunSettings, speed: float
) -> tuple[list[int], float]:
    """Samples per pose and the device-time cycle of one unit."""
    serial = f"PT{seed:06d}"
    port = tmp / f"putter{seed}"
    with VirtualPutter(seed=seed, serial=serial, speed=speed, noise_counts=noise) as putter:
        putter.serve_pty(port)
        journal = RunJournal(
            run_id=uuid.uuid4(),
            serial=serial,
            station_id="bench",
            operator_id="bench",
            started_at=datetime.now(UTC),
            poses=(*settings.poses, settings.verification_pose),
        )
        run = UnitRun(
            driver=open_unit(str(port), serial),
            journal=journal,
            journal_file=JournalFile(tmp / f"journal{seed}.json"),
            profile=load_profile(),
            settings=settings,
            reopen=lambda: open_unit(str(port), serial),
        )
        started = putter.clock.now()
        moved_to = None
        try:
            while run.phase is not Phase.DONE:
                target = run.requested
                if target is not None and target.name != moved_to and run.phase is Phase.POSE:
                    moved_to = target.name
                    putter.move_to(target.name, MOVE_S)
                run.step()
                time.sleep(0.005)
            cycle = putter.clock.now() - started
        finally:
            run.driver.close()
    record = run.record
    assert record is not None
    assert record.verdict == "pass", record.failures
    return [p.sample_count for p in record.poses], cycle


def measure(units: int, speed: float) -> list[dict[str, Any]]:
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for noise in (1.0, 2.0, 3.0):
            for mode in ("fixed", "adaptive"):
                settings = RunSettings(capture=mode)
                counts: list[int] = []
                cycles: list[float] = []
                for k in range(units):
                    c, cycle = one_unit(Path(tmp), 100 + k, noise, settings, speed)
                    counts.extend(c)
                    cycles.append(cycle)
                rows.append(
                    {
                        "noise": noise,
                        "mode": mode,
                        "mean": statistics.fmean(counts),
                        "min": min(counts),
                        "max": max(counts),
                        "windows_s": sum(counts) / units / DEFAULT_RATE_HZ,
                        "cycle_s": statistics.fmean(cycles),
                    }
                )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--speed", type=float, default=20.0)
    args = parser.parse_args()
    units = 2 if args.quick else 4
    print(
        "| noise (counts rms) | capture | samples per pose, mean (min–max) "
        "| 7 windows per unit | cycle per unit (device time) |"
    )
    print("|---|---|---|---|---|")
    for m in measure(units, args.speed):
        print(
            f"| {m['noise']:g} | {m['mode']} | {m['mean']:.0f} ({m['min']}–{m['max']}) "
            f"| {m['windows_s']:.2f} s | {m['cycle_s']:.2f} s |"
        )


if __name__ == "__main__":
    main()
