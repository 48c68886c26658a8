"""How soon a started results server answers: ``/healthz``, then the first EOL report.

    python benchmarks/bench_server_start.py             # 5 starts each, medians
    python benchmarks/bench_server_start.py --runs 9

A restarted plant server, or a container scaled up behind a load balancer, is blind
until it answers. Each start is a real ``calstation serve`` process on an embedded
SQLite database already migrated (as after the first start), timed from the spawn to
the first 200 of ``GET /healthz``, then to the first 200 of ``GET /api/v1/reports/eol``
(the report of the runs stored, a hundred by default). The baseline is the bare
``python -c "import fastapi, sqlalchemy"`` (a server cannot start before its
libraries load), timed the same way on the same machine, start by start, so the
ratios hold on a busy machine too. Targets: ``/healthz`` within 3× the
baseline, and the first report, asked once ``/healthz`` answers, within 2× the baseline
of its own. Prints a Markdown table.
"""

import argparse
import os
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx

from station.domain.record.records import RunRecord
from station.results.storage import DatabaseStore

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the test suite's record maker, below
from tests.db.records import make_record  # noqa: E402

#: How often the server is asked whether it answers yet.
POLL_S = 0.01


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _baseline() -> float:
    """Seconds for a bare interpreter to import the server's two big libraries."""
    begin = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import fastapi, sqlalchemy"], check=True)
    return time.perf_counter() - begin


def _first_200(client: httpx.Client, url: str, process: subprocess.Popen[bytes]) -> None:
    """Ask ``url`` until it answers 200: not yet listening, or 503 while it starts."""
    while True:
        if process.poll() is not None:
            raise SystemExit(f"server exited with {process.returncode} before answering")
        try:
            code = client.get(url, timeout=60).status_code
        except httpx.TransportError:
            code = None
        if code == 200:
            return
        if code not in (None, 503):
            raise SystemExit(f"{url} answered {code}")
        time.sleep(POLL_S)


def _start(url: str) -> tuple[float, float]:
    """Seconds from spawning ``calstation serve`` to ``/healthz``, then to the first report."""
    port = _free_port()
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    begin = time.perf_counter()
    process = subprocess.Popen(
        [sys.executable, "-m", "station", "serve", "--port", str(port), "--database-url", url],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        with httpx.Client(base_url=f"http://127.0.0.1:{port}") as client:
            _first_200(client, "/healthz", process)
            healthy = time.perf_counter()
            _first_200(client, "/api/v1/reports/eol", process)
            reported = time.perf_counter() - healthy
            healthy -= begin
    finally:
        process.terminate()
        process.wait(timeout=30)
    return healthy, reported


def _stored(database_url: str, runs: int) -> None:
    """A migrated database holding ``runs`` runs of as many units."""
    records: list[RunRecord] = [make_record(serial=f"PT{n:06d}") for n in range(runs)]
    with DatabaseStore(database_url) as store:
        for record in records:
            store.submit(record)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="starts to time")
    parser.add_argument("--stored", type=int, default=100, help="runs in the database")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        url = f"sqlite:///{Path(tmp) / 'results.db'}"
        _stored(url, args.stored)
        rows = []
        for _ in range(args.runs):
            base = _baseline()
            healthy, reported = _start(url)
            rows.append((base, healthy, reported))
    base = statistics.median(r[0] for r in rows)
    healthy = statistics.median(r[1] for r in rows)
    reported = statistics.median(r[2] for r in rows)
    health_ratio = statistics.median(r[1] / r[0] for r in rows)
    report_ratio = statistics.median(r[2] / r[0] for r in rows)
    print(f"{args.runs} starts, {args.stored} runs stored, load average {os.getloadavg()[0]:.1f}")
    print()
    print("| step | median s | × `import fastapi, sqlalchemy` | target |")
    print("|---|---|---|---|")
    print(f"| `import fastapi, sqlalchemy` (baseline) | {base:.2f} | 1.00 | — |")
    print(f"| spawn → first 200 of `/healthz` | {healthy:.2f} | {health_ratio:.2f} | ≤ 3 |")
    print(f"| then the first `/api/v1/reports/eol` | {reported:.2f} | {report_ratio:.2f} | ≤ 2 |")


if __name__ == "__main__":
    main()
