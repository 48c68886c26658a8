"""Results API benchmark: a real uvicorn server on PostgreSQL holding 1,000,000 runs.

    python benchmarks/bench_api.py                  # 1,000,000 runs (a few minutes)
    python benchmarks/bench_api.py --runs 100000    # smaller, quicker

Needs a PostgreSQL server (``--postgres-url``, default ``CALSTATION_TEST_POSTGRES_URL``
or ``postgresql+psycopg://postgres@127.0.0.1:5432/test``). Works in a schema of its own,
created, migrated, seeded in SQL (``generate_series``: every run with seven poses, the
failed ones with a failure reason; then the report's roll-ups and each unit's current
state, as their migrations build them) and dropped at the end.

Measures, with ``--clients`` concurrent keep-alive HTTP clients (default 32):
(a) ``GET /api/v1/units/{serial}`` of random serials: requests/s and latency with every
    client sending as fast as it is answered (the throughput), then p50/p99 latency at an
    offered ``--rate`` (default 1,000/s) spread over the same clients, each request timed
    from when it was due;
(b) ``POST /api/v1/runs`` of new runs (each recomputed by the server): submissions/s
    as fast as answered; then unit lookups at ``--rate`` again while stations submit
    ``--submit-rate`` runs/s (default 10/s) beside them;
(c) list queries (``GET /api/v1/runs`` filtered by station, verdict and time, serial;
    the second page through the cursor) and ``GET /api/v1/runs/{id}``: p50/p99.
Targets: unit lookup p99 < 20 ms and at least 1,000 lookups/s.
"""

import argparse
import asyncio
import os
import random
import re
import secrets
import statistics
import subprocess
import sys
import time
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from datetime import UTC, datetime, timedelta
from pathlib import Path
from urllib.parse import urlencode

import httpx
import numpy as np
import uvloop
from sqlalchemy import insert, make_url, text

from db import RunRepository, make_engine, open_database
from db.models import StoredLimitsProfile
from db.rollups import rebuild
from db.store import profile_row
from station.domain.calibration import solve
from station.domain.product.limits import load_profile
from station.domain.record.records import RunRecord
from station.simulator.recording import pose_means, six_directions
from station.simulator.sensor import SensorTruth

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_URL = "postgresql+psycopg://postgres@127.0.0.1:5432/test"
UNITS_PER_RUN = 0.4  # 1,000,000 runs → 400,000 serial numbers, 2.5 runs each
STATIONS = 8
T0 = datetime(2026, 1, 1, tzinfo=UTC)
STEP_S = 15  # one run every 15 s across the plant
#: What a station sends of its limits profile: the reference and the profile itself.
LIMITS = load_profile().ref.model_dump(mode="json")
POST_RUNS = 3000  # at most, submitted as fast as answered

#: The register of runs first (numbered 1…runs), then the runs under those numbers.
SEED_RUN_IDS_SQL = """
INSERT INTO run_ids (run_pk, run_id, started_at)
SELECT g, gen_random_uuid(), :t0 + make_interval(secs => g * :step)
FROM generate_series(1, :runs) AS g;
SELECT setval('run_ids_run_pk_seq', :runs)
"""

SEED_SQL = """
INSERT INTO runs (id, run_id, serial, station_id, operator_id, started_at, finished_at,
    received_at, software_version, algorithm, model, limits_name, limits_version,
    limits_sha256, verdict, offset_x, offset_y, offset_z, sensitivity_x, sensitivity_y,
    sensitivity_z, matrix, residual_rms_mg, residual_max_mg, condition_number,
    verification_error_mg, gyro, record_sha256, part_number)
SELECT g, run_id,
       'PT-' || lpad((g % :units)::text, 7, '0'),
       'line' || (g % :stations / 4 + 1) || '-st' || (g % :stations % 4 + 1),
       'op-' || (g % 40),
       :t0 + make_interval(secs => g * :step),
       :t0 + make_interval(secs => g * :step + 95),
       :t0 + make_interval(secs => g * :step + 96),
       '1.4.0', 'autocal-ls', 'six', 'kxm52-production', '1', :limits_sha256,
       CASE WHEN hashint % 100 < 8 THEN 'fail' ELSE 'pass' END,
       2048 + hashint % 200 - 100, 2048 + hashint % 180 - 90, 2048 + hashint % 160 - 80,
       819.2 + hashint % 40 - 20, 819.2 + hashint % 30 - 15, 819.2 + hashint % 20 - 10,
       jsonb_build_array(jsonb_build_array(0.00122, 0, 0), jsonb_build_array(0, 0.00122, 0),
                         jsonb_build_array(0, 0, 0.00122)),
       0.4, 0.9, 3.2, 0.7,
       '{"bias": {"x": 0.01, "y": -0.02, "z": 0.005},
         "noise": {"x": 0.05, "y": 0.05, "z": 0.06}}'::jsonb,
       md5(g::text) || md5((g + 1)::text),
       'DIXX-A12'
FROM (SELECT g, abs(hashint4(g)) AS hashint FROM generate_series(1, :runs) AS g) AS s
JOIN run_ids ON run_pk = g
"""

SEED_POSES_SQL = """
INSERT INTO poses (run_pk, started_at, index, name, role, mean_x, mean_y, mean_z, std_x,
    std_y, std_z, sample_count, gyro_x, gyro_y, gyro_z, temperature_c, crc_errors, gaps,
    resyncs, lost_samples, replaced)
SELECT r.id, r.started_at, p, 'pose' || p, CASE WHEN p = 6 THEN 'verify' ELSE 'fit' END,
       r.offset_x + 800 * (p % 3 = 0)::int, r.offset_y + 800 * (p % 3 = 1)::int,
       r.offset_z + 800 * (p % 3 = 2)::int, 1.1, 1.2, 1.3, 1024, 0.01, -0.02, 0.005, 24.5,
       0, 0, 0, 0, '[]'::jsonb
FROM runs AS r CROSS JOIN generate_series(0, 6) AS p
"""

SEED_FAILURES_SQL = """
INSERT INTO run_failures (run_pk, position, code, message, measured, lower, upper, axis)
SELECT id, 0, 'sensitivity_out_of_range', 'sensitivity z above 819.0', sensitivity_z,
       778.2, 819.0, 'z'
FROM runs WHERE verdict = 'fail'
"""


@dataclass
class Result:
    """Latencies (s) of the successful requests, wall time, CPU time of server and client."""

    latencies: list[float]
    wall_s: float
    errors: int
    server_cpu_s: float = 0.0
    client_cpu_s: float = 0.0
    cpu_shared: bool = False  # measured over the same time as another load's requests

    @property
    def requests(self) -> int:
        """Requests sent, answered or refused."""
        return len(self.latencies) + self.errors

    def row(self, name: str, clients: int) -> str:
        """One Markdown table row."""
        ms = sorted(1e3 * x for x in self.latencies)
        p50 = statistics.median(ms)
        p99 = ms[min(len(ms) - 1, int(0.99 * len(ms)))]
        rate = len(ms) / self.wall_s
        n = max(1, self.requests)
        cpu = (
            "(above) | (above)"
            if self.cpu_shared
            else f"{1e3 * self.server_cpu_s / n:.2f} | {1e3 * self.client_cpu_s / n:.2f}"
        )
        return (
            f"| {name} | {clients} | {len(ms)} | {p50:.1f} | {p99:.1f} | {rate:,.0f} | "
            f"{cpu} | {self.errors} |"
        )

    def together(self, other: "Result") -> tuple["Result", "Result"]:
        """Two loads run side by side: the CPU of both is counted over all their requests."""
        n = max(1, self.requests)
        share = n / max(1, n + other.requests)
        mine = replace(
            self, server_cpu_s=self.server_cpu_s * share, client_cpu_s=self.client_cpu_s * share
        )
        return mine, replace(other, cpu_shared=True)


def tree_cpu_s(pid: int) -> float:
    """CPU time (user + system) of process ``pid`` and its children, seconds (Linux /proc)."""
    tick = os.sysconf("SC_CLK_TCK")
    children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    total = 0.0
    for each in [pid, *map(int, children)]:
        fields = Path(f"/proc/{each}/stat").read_text().rsplit(")", 1)[1].split()
        total += (int(fields[11]) + int(fields[12])) / tick
    return total


@contextmanager
def bench_schema(server_url: str) -> Iterator[str]:
    """A fresh schema for the benchmark; yields a URL working in it; drops it at the end."""
    schema = f"calstation_bench_{os.getpid()}_{secrets.token_hex(3)}"
    admin = make_engine(server_url, isolation_level="AUTOCOMMIT")
    with admin.connect() as connection:
        connection.execute(text(f'CREATE SCHEMA "{schema}"'))
    try:
        url = make_url(server_url).update_query_dict({"options": f"-csearch_path={schema}"})
        yield url.render_as_string(hide_password=False)
    finally:
        with admin.connect() as connection:
            connection.execute(text(f'DROP SCHEMA "{schema}" CASCADE'))
        admin.dispose()


def seed(url: str, runs: int) -> tuple[str, int]:
    """Migrate and fill the schema; return a station API key and the unit count."""
    database = open_database(url, auto_migrate=True)
    units = max(1, int(runs * UNITS_PER_RUN))
    started = time.perf_counter()
    with database.engine.begin() as connection:
        for statement in SEED_RUN_IDS_SQL.split(";"):
            connection.execute(text(statement), {"t0": T0, "step": STEP_S, "runs": runs})
        connection.execute(
            text(SEED_SQL),
            {
                "units": units,
                "stations": STATIONS,
                "t0": T0,
                "step": STEP_S,
                "runs": runs,
                "limits_sha256": load_profile().sha256,
            },
        )
        connection.execute(text(SEED_POSES_SQL))
        connection.execute(text(SEED_FAILURES_SQL))
        connection.execute(text("ANALYZE runs; ANALYZE poses; ANALYZE run_failures"))
        connection.execute(
            insert(StoredLimitsProfile), profile_row(load_profile())
        )  # as the first run stored it
        rebuild(connection)  # the report's facts and roll-ups, as the migration builds them
    seeded = time.perf_counter()
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        repository.refresh_units()  # each unit's current state, as an upgrade writes it
        key = repository.create_key("line1-st1")
    filled = time.perf_counter()
    with database.engine.connect().execution_options(isolation_level="AUTOCOMMIT") as c:
        c.execute(text("VACUUM ANALYZE"))
        # Seeding and VACUUM leave gigabytes of dirty pages. Written out during the
        # measurement, they would make lookups wait on the disk: a plant's server, which
        # stores a run every few seconds, never has that backlog.
        c.execute(text("CHECKPOINT"))
    print(
        f"seeded {runs:,} runs ({7 * runs:,} poses) and their report roll-ups in "
        f"{seeded - started:.0f} s, their {units:,} units' current state in {filled - seeded:.0f} s"
    )
    database.dispose()
    return key, units


@contextmanager
def server(url: str, workers: int, port: int) -> Iterator[tuple[str, int]]:
    """``calstation serve`` as a real process; yields its base URL and pid once it answers."""
    env = {**os.environ, "CALSTATION_DATABASE_URL": url, "PYTHONPATH": str(ROOT)}
    command = [sys.executable, "-m", "station", "serve", "--port", str(port)]
    process = subprocess.Popen(  # its log (a line per submission) is not the result
        [*command, "--workers", str(workers)],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    base = f"http://127.0.0.1:{port}"
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                if httpx.get(f"{base}/healthz", timeout=1).status_code == 200:
                    break
            except httpx.TransportError:
                pass
            if time.monotonic() > deadline or process.poll() is not None:
                raise SystemExit("the server did not start")
            time.sleep(0.2)
        yield base, process.pid
    finally:
        process.terminate()
        process.wait(timeout=20)


#: One request of the load: method, target (path and query), body.
Call = tuple[str, str, bytes]


class Connection:
    """One keep-alive HTTP/1.1 connection of the load generator.

    Deliberately minimal: httpx spends more CPU per request than the server does, and on
    one 2-core machine the load generator's CPU is taken from the server under test.
    """

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, head: str):
        self.reader, self.writer, self.head = reader, writer, head

    @classmethod
    async def open(cls, base: str, headers: dict[str, str]) -> "Connection":
        url = httpx.URL(base)
        assert url.port is not None
        reader, writer = await asyncio.open_connection(url.host, url.port)
        head = "".join(f"{k}: {v}\r\n" for k, v in {"Host": url.host, **headers}.items())
        return cls(reader, writer, head)

    async def send(self, call: Call) -> int:
        """Send one request, read the whole answer, return its status."""
        method, target, body = call
        self.writer.write(
            f"{method} {target} HTTP/1.1\r\n{self.head}Content-Length: {len(body)}\r\n\r\n".encode()
            + body
        )
        head = await self.reader.readuntil(b"\r\n\r\n")
        length = re.search(rb"(?i)\r\ncontent-length: *(\d+)", head)
        assert length is not None, head
        await self.reader.readexactly(int(length[1]))
        return int(head[9:12])

    def close(self) -> None:
        self.writer.close()


async def measure(
    base: str,
    server_pid: int,
    clients: int,
    seconds: float,
    call: Callable[[random.Random], Call],
    expect: tuple[int, ...] = (200,),
    total: int | None = None,
    headers: dict[str, str] | None = None,
    rate: float | None = None,
) -> Result:
    """``clients`` keep-alive connections issuing calls for ``seconds`` (or ``total`` calls).

    Without ``rate``, each connection sends its next request as soon as the answer to the
    last one is in (closed loop: the server's throughput). With ``rate``, the
    connections send ``rate`` requests per second between them on a fixed schedule, and
    a request's latency counts from when it was due, not from when a late connection
    got round to sending it (open loop: latency at a given load, without coordinated
    omission).
    """
    latencies: list[float] = []
    errors = 0
    connections = [await Connection.open(base, headers or {}) for _ in range(clients)]
    for connection in connections:
        assert await connection.send(("GET", "/healthz", b"")) == 200
    issued = 0
    began, server0, client0 = time.perf_counter(), tree_cpu_s(server_pid), time.process_time()
    stop = began + seconds

    async def worker(connection: Connection, seed: int) -> None:
        nonlocal errors, issued
        rng = random.Random(seed)
        interval = clients / rate if rate else 0.0
        due = began + interval * seed / clients
        while time.perf_counter() < stop and (total is None or issued < total):
            issued += 1
            if rate:
                await asyncio.sleep(max(0.0, due - time.perf_counter()))
                started, due = due, due + interval
            else:
                started = time.perf_counter()
            if await connection.send(call(rng)) in expect:
                latencies.append(time.perf_counter() - started)
            else:
                errors += 1

    await asyncio.gather(*(worker(c, i) for i, c in enumerate(connections)))
    result = Result(
        latencies,
        time.perf_counter() - began,
        errors,
        server_cpu_s=tree_cpu_s(server_pid) - server0,
        client_cpu_s=time.process_time() - client0,
    )
    for connection in connections:
        connection.close()
    return result


def new_record(rng: random.Random, np_rng: np.random.Generator, index: int) -> RunRecord:
    """A fresh passing run whose coefficients are what the server will recompute."""
    unit = SensorTruth.draw_accelerometer(np_rng)
    directions = np.vstack([six_directions(np_rng, tilt_deg=3.0), [[0.577, 0.577, 0.577]]])
    means = pose_means(unit, directions, 0.05, np_rng)
    calibration = solve(means[:6], "six").calibration
    started = datetime.now(UTC) + timedelta(seconds=index)
    xyz = ("x", "y", "z")
    return RunRecord.model_validate(
        {
            "run_id": str(uuid.UUID(int=rng.getrandbits(128), version=4)),
            "serial": f"PN-{index:08d}",
            "station_id": "line1-st1",
            "operator_id": "op-1",
            "started_at": started.isoformat(),
            "finished_at": (started + timedelta(seconds=95)).isoformat(),
            "software_version": "1.4.0",
            "algorithm": "autocal-ls",
            "model": "six",
            "limits": LIMITS,  # the reference and the profile, as a station sends them
            "verdict": "pass",
            "coefficients": {
                "offset": dict(zip(xyz, calibration.offset.tolist(), strict=True)),
                "sensitivity": dict(zip(xyz, calibration.sensitivity.tolist(), strict=True)),
                "matrix": calibration.matrix.tolist(),
            },
            "quality": {"residual_rms_mg": 0.3, "residual_max_mg": 0.6, "condition_number": 2.0},
            "poses": [
                {
                    "index": i,
                    "name": f"pose{i}",
                    "role": "verify" if i == 6 else "fit",
                    "mean": dict(zip(xyz, means[i].tolist(), strict=True)),
                    "std": {"x": 1.0, "y": 1.0, "z": 1.0},
                    "sample_count": 1024,
                }
                for i in range(7)
            ],
        }
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=1_000_000)
    parser.add_argument("--clients", type=int, default=32)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seconds", type=float, default=15.0)
    parser.add_argument(
        "--rate", type=float, default=1000.0, help="offered unit lookups/s of the paced run"
    )
    parser.add_argument(
        "--submit-rate",
        type=float,
        default=10.0,
        help="submissions/s from the stations while lookups run at --rate",
    )
    parser.add_argument("--port", type=int, default=8765)
    parser.add_argument(
        "--postgres-url", default=os.environ.get("CALSTATION_TEST_POSTGRES_URL", DEFAULT_URL)
    )
    args = parser.parse_args()
    load_before = os.getloadavg()

    with bench_schema(args.postgres_url) as url:
        key, units = seed(url, args.runs)
        with server(url, args.workers, args.port) as (base, pid):

            def lookup(rng: random.Random) -> Call:
                return ("GET", f"/api/v1/units/PT-{rng.randrange(units):07d}", b"")

            unit = uvloop.run(measure(base, pid, args.clients, args.seconds, lookup))
            paced = uvloop.run(
                measure(base, pid, args.clients, args.seconds, lookup, rate=args.rate)
            )
            np_rng = np.random.default_rng(7)
            rng = random.Random(7)
            beside = int(args.submit_rate * args.seconds * 1.2) + 10
            posts = [
                new_record(rng, np_rng, i).model_dump_json().encode()
                for i in range(POST_RUNS + beside)
            ]
            queue = iter(posts)
            stations = {"Authorization": f"Bearer {key}", "Content-Type": "application/json"}

            def submit(_: random.Random) -> Call:
                return ("POST", "/api/v1/runs", next(queue))

            post = uvloop.run(
                measure(
                    base,
                    pid,
                    args.clients,
                    args.seconds,
                    submit,
                    expect=(201,),
                    total=POST_RUNS,
                    headers=stations,
                )
            )
            # Each station sends at least once a second: the server's keep-alive
            # timeout (5 s) would close a connection left idle for longer.
            submitters = max(1, min(STATIONS, int(args.submit_rate)))

            async def mixed() -> tuple[Result, Result]:
                return await asyncio.gather(
                    measure(base, pid, args.clients, args.seconds, lookup, rate=args.rate),
                    measure(
                        base,
                        pid,
                        submitters,
                        args.seconds,
                        submit,
                        expect=(201,),
                        headers=stations,
                        rate=args.submit_rate,
                    ),
                )

            paced_mixed, submitted = uvloop.run(mixed())
            # Both loads were timed over the same seconds: their CPU is one figure.
            paced_mixed, submitted = paced_mixed.together(submitted)
            runs = "/api/v1/runs"
            page = httpx.get(
                f"{base}{runs}", params={"station_id": "line2-st3", "limit": 50}
            ).json()
            some_run = page["data"][0]["run_id"]
            t_mid = T0 + timedelta(seconds=STEP_S * args.runs // 2)
            by_time = urlencode(
                {
                    "verdict": "fail",
                    "since": t_mid.isoformat(),
                    "until": (t_mid + timedelta(days=1)).isoformat(),
                }
            )
            second = urlencode(
                {"station_id": "line2-st3", "limit": 50, "cursor": page["next_cursor"]}
            )
            lists: dict[str, Callable[[random.Random], Call]] = {
                "GET /runs?station_id (50)": lambda _: (
                    "GET",
                    f"{runs}?station_id=line2-st3&limit=50",
                    b"",
                ),
                "GET /runs?station_id, 2nd page": lambda _: ("GET", f"{runs}?{second}", b""),
                "GET /runs?verdict=fail&since&until (100)": lambda _: (
                    "GET",
                    f"{runs}?{by_time}",
                    b"",
                ),
                "GET /runs?serial": lambda rng: (
                    "GET",
                    f"{runs}?serial=PT-{rng.randrange(units):07d}",
                    b"",
                ),
                "GET /units/{serial}/runs": lambda rng: (
                    "GET",
                    f"/api/v1/units/PT-{rng.randrange(units):07d}/runs",
                    b"",
                ),
                "GET /runs/{run_id} (7 poses)": lambda _: ("GET", f"{runs}/{some_run}", b""),
            }
            list_results = {
                name: uvloop.run(measure(base, pid, 8, args.seconds / 3, call))
                for name, call in lists.items()
            }

    print()
    print(f"{args.runs:,} runs, {units:,} units; server: {args.workers} uvicorn workers")
    print()
    print(f"load average before the run: {load_before}; after: {os.getloadavg()}")
    print()
    print(
        "| request | clients | requests | p50 ms | p99 ms | per s "
        "| server CPU ms/req | client CPU ms/req | errors |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    print(unit.row("GET /api/v1/units/{serial}, as fast as answered", args.clients))
    print(paced.row(f"GET /api/v1/units/{{serial}} at {args.rate:,.0f}/s", args.clients))
    print(
        paced_mixed.row(
            f"GET /api/v1/units/{{serial}} at {args.rate:,.0f}/s, "
            f"stations submitting {args.submit_rate:,.0f}/s",
            args.clients,
        )
    )
    print(submitted.row(f"POST /api/v1/runs at {args.submit_rate:,.0f}/s, beside it", submitters))
    print(post.row("POST /api/v1/runs, as fast as answered", args.clients))
    for name, result in list_results.items():
        print(result.row(name, 8))


if __name__ == "__main__":
    main()
