"""``calstation solve LOG.csv --stream``: wall time and peak memory against the log's length.

Twelve-pose streams (500 samples/s, nine-parameter accelerometer) with longer and
longer stills, written as CSV and solved by the real command in a fresh process;
peak memory is the child's maximum resident set size.

Run: ``python benchmarks/bench_stream_solve.py``. Prints a Markdown table.
"""

import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from station.simulator.recording import (
    StreamPlan,
    pose_orientations,
    random_imu,
    recorded_stream,
    spread_directions,
)

ROWS = (20_000, 200_000, 1_000_000)


def main() -> None:
    print("| rows | log size | wall time | peak memory (RSS) | stills found |")
    print("| --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as tmp:
        for rows in ROWS:
            still_s = (rows / 500.0 - 11 * 1.5) / 12
            rng = np.random.default_rng(rows)
            imu = random_imu(rng)
            stream = recorded_stream(
                rng,
                imu,
                pose_orientations(rng, spread_directions(12)),
                StreamPlan(still_s=still_s),
            )
            path = Path(tmp) / f"log{rows}.csv"
            np.savetxt(
                path,
                np.column_stack([stream.t, stream.accel_counts, stream.gyro_dps]),
                delimiter=",",
                header="t,ax,ay,az,gx,gy,gz",
                comments="",
                fmt="%.6f",
            )
            start = time.perf_counter()
            command = [sys.executable, "-m", "station", "solve", str(path), "--stream"]
            done = subprocess.run(
                [*command, "--model", "nine", "--json"],
                capture_output=True,
                text=True,
                check=True,
            )
            wall = time.perf_counter() - start
            peak_mb = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
            poses = done.stdout.split('"poses": ')[1].split(",")[0]
            print(
                f"| {len(stream.t):,} | {path.stat().st_size / 1e6:.0f} MB | {wall:.1f} s "
                f"| {peak_mb:.0f} MB | {poses} |",
                flush=True,
            )


if __name__ == "__main__":
    main()
