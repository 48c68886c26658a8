"""The station's own overhead per unit, beyond the physics of taking the poses.

    python benchmarks/bench_station.py            # 3 units at 10× and 1 unit in real time
    python benchmarks/bench_station.py --quick    # 2 units at 10× only

A unit cannot be calibrated faster than its physics allows: the operator moves it
into each pose and it settles (the virtual putter knows when its tremor has died
down), then seven still windows of 1024 samples at the device rate are taken, then
256 calibrated samples check the unit's own output. Everything the station spends
beyond that (waiting for window evaluations, solving, write-back, journal, outbox,
database, screens) is its overhead, reported against the seven windows' time.
Target: under 5 %.
"""

import argparse
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

from rich.console import Console

from station.app import StationApp
from station.config import StationConfig
from station.demo import ScriptedOperator
from station.device.protocol import DEFAULT_RATE_HZ
from station.limits import load_profile
from station.session import UNIT_OUTPUT_SAMPLES
from station.storage import DatabaseStore


@dataclass
class TimedOperator(ScriptedOperator):
    """The demo's operator, noting the device time each move and its settling take."""

    handling_s: list[float] = field(default_factory=list)
    scanned_at: list[float] = field(default_factory=list)
    _last: str | None = None

    def read(self) -> str:
        keys = super().read()
        if keys.endswith("\n"):
            self.scanned_at.append(time.perf_counter())
            self._last = None
        current = self._current
        if current is not None and self._moved_to != self._last:
            self._last = self._moved_to
            putter = current.putter
            self.handling_s.append(max(0.0, putter.settled_at_s - putter.clock.now()))
        return keys


def measure(units: int, speed: float) -> tuple[float, float, float]:
    """Wall time per unit, physics per unit, overhead as a fraction of 7 windows."""
    with tempfile.TemporaryDirectory() as tmp:
        data = Path(tmp)
        port = data / "putter"
        config = StationConfig(
            data_dir=data, port=str(port), database_url=f"sqlite:///{data}/r.sqlite3"
        )
        operator = TimedOperator(units=units, port=port, seed=7, speed=speed)
        app = StationApp(
            config=config,
            profile=load_profile(),
            open_store=lambda: DatabaseStore(config.database_url),
            keys=operator,
            console=Console(quiet=True),
            units=units,
        )
        operator.station = app
        start = time.perf_counter()
        try:
            records = app.serve()
        finally:
            operator.close()
        wall = time.perf_counter() - start
    assert all(r.verdict == "pass" for r in records), [r.failures for r in records]
    window_s = 1024 / DEFAULT_RATE_HZ / speed
    windows = 7 * window_s
    physics = (sum(operator.handling_s) / speed) + units * (
        windows + UNIT_OUTPUT_SAMPLES / DEFAULT_RATE_HZ / speed
    )
    overhead = (wall - physics) / units
    return wall / units, physics / units, overhead / windows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    runs = [(2, 10.0)] if args.quick else [(3, 10.0), (1, 1.0)]
    print("| units | clock | wall per unit | physics per unit | station overhead (of 7 windows) |")
    print("|---|---|---|---|---|")
    for units, speed in runs:
        wall, physics, overhead = measure(units, speed)
        print(f"| {units} | {speed:g}× | {wall:.2f} s | {physics:.2f} s | {overhead:.1%} |")


if __name__ == "__main__":
    main()
