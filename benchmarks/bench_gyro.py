"""Gyro g-sensitivity: compensation throughput, and the time to read and fit a lab log.

Run: ``python benchmarks/bench_gyro.py``. Prints a results table (best of 5 runs).
"""

import io
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from station.domain.gyro.compensation import compensate
from station.domain.gyro.fit import fit_log
from station.domain.gyro.log import read_log, write_log
from station.domain.gyro.simulate import paper_truth, simulate_log

REPEATS = 5


def best_of(action: Callable[[], object]) -> float:
    """Shortest wall time of ``REPEATS`` runs, seconds."""
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        action()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    model = paper_truth()
    rng = np.random.default_rng(0)
    rows = ["| task | size | best time | throughput |", "| --- | --- | --- | --- |"]
    for n in (1_000, 10_000, 100_000, 1_000_000):
        rate = rng.uniform(-600.0, 600.0, (n, 3))
        acc = rng.uniform(-30.0, 30.0, (n, 3))
        gyro = model.predict(rate, acc)
        seconds = best_of(lambda g=gyro, a=acc: compensate(model, g, a))
        rows.append(
            f"| compensate | {n:,} samples | {seconds * 1e3:.2f} ms | "
            f"{n / seconds / 1e6:.2f} M samples/s |"
        )
    log, _ = simulate_log(model, seed=1)
    seconds = best_of(lambda: fit_log(log))
    rows.append(
        f"| fit (identifiability, fit, comparison) | {len(log)} dwells | "
        f"{seconds * 1e3:.1f} ms | — |"
    )
    samples, segments = simulate_log(model, samples_per_dwell=100, seed=1)
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "log.csv"
        buffer = io.StringIO()
        write_log(buffer, samples, segments)
        path.write_text(buffer.getvalue(), encoding="utf-8")
        seconds = best_of(lambda: read_log(path))
    rows.append(
        f"| read_log with segment averaging | {len(samples):,} rows | {seconds * 1e3:.0f} ms | "
        f"{len(samples) / seconds / 1e3:.0f} k rows/s |"
    )
    print("\n".join(rows))


if __name__ == "__main__":
    main()
