"""Beyond one machine: servers behind HAProxy on pgbouncer, one of them killed mid-run.

    python benchmarks/bench_scale_out.py                 # 60 s a phase, about 4 minutes
    python benchmarks/bench_scale_out.py --seconds 20    # quicker
    python benchmarks/bench_scale_out.py --replica       # the report from a streaming replica

Needs the distribution's ``haproxy`` and ``pgbouncer`` (``apt-get install haproxy
pgbouncer``) and a PostgreSQL server (``--postgres-url``, default
``CALSTATION_TEST_POSTGRES_URL`` or the local ``test`` database). The benchmark starts its
own instances of each on free ports, from configuration files it writes into a temporary
directory (never the system services), and ends them at the end. It works in a database
of its own (``CREATE DATABASE``, dropped at the end; pgbouncer forwards no
``search_path`` option), migrated and seeded as :mod:`bench_api` seeds it (``--runs``),
with an API key per station.

Two phases of ``--seconds`` each, the same load: ``--stations`` stations (default 32),
each submitting its next run (``POST /api/v1/runs``, a valid run as :mod:`bench_api`
builds it) as soon as the last one is stored, and retrying the same run (same
``run_id``) after any error or 5xx until it is stored; ``--readers`` readers (default 60)
asking for the end-of-line report (``GET /api/v1/reports/eol``, JSON, the whole range) as
soon as the last answer is in.

(a) the baseline: one ``calstation serve`` on PostgreSQL directly, no proxy;
(b) ``--servers`` servers (default 3), each on pgbouncer (transaction pooling), behind
    HAProxy (``leastconn``, health checks on ``/healthz``, a request that found its
    server gone retried on another: ``retry-on``, ``option redispatch``). A third of the
    way in, one server is killed (SIGKILL) and started again on its port. Every server
    watches an alert rule that fires on the seeded runs (``[[cpk]]`` with an unreachable
    target) and posts to a webhook receiver of the benchmark.

With ``--replica`` the benchmark runs a PostgreSQL primary and a streaming replica of its
own instead (``initdb`` and ``pg_basebackup -R`` in a temporary directory, each
``postgres`` on a free port, run as the ``postgres`` user): the servers of (b) read the
report from the replica (``CALSTATION_REPORT_DATABASE_URL``, directly, not through
pgbouncer); during (b) the replica's lag is sampled every second on the primary
(``pg_stat_replication``: ``replay_lag``, and the WAL bytes sent but not yet replayed),
after (b) measured once more (WAL bytes behind, the time to replay them), and its runs
compared with the primary's.

Checks after (b): every run a station saw stored is in the database exactly once and
no other run of the load is there; the alert was posted exactly once; the 5xx answers
readers saw, inside and outside the kill's window (from the kill until HAProxy's next
health check passed on the restarted server). Prints submissions/s, p50/p95 report
latency of each phase and the checks' figures; exits 1 if a check fails.
"""

import argparse
import asyncio
import collections
import contextlib
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from bench_api import DEFAULT_URL, ROOT, Connection, new_record
from sqlalchemy import make_url, text

from db import RunRepository, make_engine, open_database

sys.path.insert(0, str(ROOT))  # the scale-out parts the tests start, below
from tests.databases import own_postgres_database
from tests.scale_out import CHECK_MS, Webhook, haproxy, pgbouncer, start_server, stop
from tests.servers import free_port

EOL = "/api/v1/reports/eol?format=json"
RUNS = "/api/v1/runs"
#: Seconds a station waits before it sends a run again that was not stored.
RETRY_S = 0.2


@dataclass
class Load:
    """What the clients saw: runs stored, report latencies and error answers in time."""

    stored: dict[str, str] = field(default_factory=dict)  # run_id → station
    retries: int = 0
    latencies: list[float] = field(default_factory=list)
    reader_errors: list[tuple[float, int]] = field(default_factory=list)  # (answered, status)
    station_errors: list[tuple[float, int]] = field(default_factory=list)


def own_database(server_url: str) -> AbstractContextManager[str]:
    """A database of its own for the benchmark, dropped (its connections ended) at the end."""
    return own_postgres_database("calstation_scale", server_url)


#: Run as the ``postgres`` user when started by root (PostgreSQL refuses root).
AS_POSTGRES = {"user": "postgres"} if os.geteuid() == 0 else {}


def _accepting(url: str) -> bool:
    try:
        engine = make_engine(url)
        with engine.connect() as connection:
            connection.execute(text("SELECT 1"))
        engine.dispose()
        return True
    except Exception:
        return False


@contextmanager
def own_cluster() -> Iterator[tuple[str, str]]:
    """A PostgreSQL primary and its streaming replica, each a ``postgres`` of its own on a
    free port in a temporary directory: the primary made by ``initdb`` (whose
    ``pg_hba.conf`` lets 127.0.0.1 replicate), the replica by ``pg_basebackup -R`` (a hot
    standby streaming from it). Yields the URLs of their ``postgres`` databases."""
    binaries = sorted(Path("/usr/lib/postgresql").glob("*/bin"))[-1]
    root = Path(tempfile.mkdtemp(prefix="calstation-cluster-"))
    root.chmod(0o755)
    if os.geteuid() == 0:
        shutil.chown(root, "postgres")
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL, **AS_POSTGRES}
    initdb = [str(binaries / "initdb"), "-D", str(root / "primary"), "-U", "postgres"]
    subprocess.run([*initdb, "--auth=trust", "-E", "UTF8"], check=True, **quiet)
    processes = []
    urls: list[str] = []
    try:
        for name in ("primary", "replica"):
            port = free_port()
            if name == "replica":
                source = ["-h", "127.0.0.1", "-p", str(make_url(urls[0]).port), "-U", "postgres"]
                copy = [str(binaries / "pg_basebackup"), *source, "-D", str(root / name)]
                subprocess.run([*copy, "-R", "-X", "stream"], check=True, **quiet)
            command = [str(binaries / "postgres"), "-D", str(root / name), "-p", str(port)]
            command += ["-k", str(root), "-c", "listen_addresses=127.0.0.1"]
            with (root / f"{name}.log").open("ab") as log:
                processes.append(subprocess.Popen(command, stdout=log, stderr=log, **AS_POSTGRES))
            urls.append(f"postgresql+psycopg://postgres@127.0.0.1:{port}/postgres")
            deadline = time.monotonic() + 120
            while not _accepting(urls[-1]):
                if time.monotonic() > deadline or processes[-1].poll() is not None:
                    raise SystemExit(f"the {name} PostgreSQL did not start ({root / name}.log)")
                time.sleep(0.2)
        yield urls[0], urls[1]
    finally:
        for process in reversed(processes):
            process.send_signal(signal.SIGINT)  # PostgreSQL's fast shutdown
            process.wait(timeout=60)
        shutil.rmtree(root, ignore_errors=True)


def replica_lag(primary: str, replica: str) -> tuple[float, float]:
    """(seconds, bytes) the replica is behind: wait for it to replay what the primary has
    written now, and return the time that took and the WAL bytes it was behind."""
    with make_engine(primary).connect() as connection:
        written = connection.execute(text("SELECT pg_current_wal_lsn()::text")).scalar_one()
    engine = make_engine(replica)
    started = time.monotonic()
    with engine.connect() as connection:
        behind = connection.execute(
            text("SELECT pg_wal_lsn_diff(:lsn, pg_last_wal_replay_lsn())"), {"lsn": written}
        ).scalar_one()
        while connection.execute(
            text("SELECT pg_wal_lsn_diff(:lsn, pg_last_wal_replay_lsn()) > 0"), {"lsn": written}
        ).scalar_one():
            connection.rollback()
            time.sleep(0.01)
    engine.dispose()
    return time.monotonic() - started, float(behind)


#: Seconds between two samples of the replica's lag during the load.
LAG_EVERY_S = 1.0


class LagSampler:
    """The replica's lag as the primary at ``primary_url`` sees it, every
    :data:`LAG_EVERY_S` seconds for the ``seconds`` the stations submit: ``replay_lag`` of
    ``pg_stat_replication`` (from a commit's WAL written on the primary to its replay on
    the replica; null once the replica has caught up and nothing new is written: 0) and
    the WAL bytes between the primary's current position and the replica's replay."""

    QUERY = (
        "SELECT coalesce(extract(epoch FROM replay_lag), 0)::float, "
        "pg_wal_lsn_diff(pg_current_wal_lsn(), replay_lsn)::float FROM pg_stat_replication"
    )

    def __init__(self, primary_url: str, seconds: float) -> None:
        self.duration = seconds
        self.seconds: list[float] = []
        self.bytes: list[float] = []
        self.missing = 0  # samples where no replica was connected
        self._stop = threading.Event()
        self._engine = make_engine(primary_url, isolation_level="AUTOCOMMIT")
        self._thread = threading.Thread(target=self._sample)

    def _sample(self) -> None:
        until = time.monotonic() + self.duration
        with self._engine.connect() as connection:
            while not self._stop.wait(LAG_EVERY_S) and time.monotonic() <= until:
                row = connection.execute(text(self.QUERY)).first()
                if row is None:
                    self.missing += 1
                else:
                    self.seconds.append(row[0])
                    self.bytes.append(row[1])

    def __enter__(self) -> "LagSampler":
        self._thread.start()
        return self

    def __exit__(self, *_: object) -> None:
        self._stop.set()
        self._thread.join()
        self._engine.dispose()

    def summary(self) -> str:
        """p50 / p95 / max of the samples."""

        def spread(values: list[float], scale: float) -> str:
            figures = (np.percentile(values, 50), np.percentile(values, 95), max(values))
            return " / ".join(f"{f * scale:,.0f}" for f in figures) if values else "none"

        return (
            f"replica lag during the load ({len(self.seconds)} samples, one a second; "
            f"{self.missing} without a replica): replay_lag p50 / p95 / max "
            f"{spread(self.seconds, 1000)} ms, WAL not yet replayed {spread(self.bytes, 1)} bytes"
        )


async def station(
    base: str, key: str, name: str, index: int, until: float, load: Load, t0: float
) -> None:
    """Submit runs until ``until``; each one again after any error until it is stored."""
    rng, np_rng = random.Random(f"{t0}-{index}"), np.random.default_rng(index)
    headers = {"Authorization": f"Bearer {key}", "Content-Type": "application/json"}
    connection: Connection | None = None
    count = 0
    while time.monotonic() < until:
        record = new_record(rng, np_rng, index * 1_000_000 + count)
        record = record.model_copy(
            update={"station_id": name, "serial": f"S{index:02d}-{count:07d}"}
        )
        body = record.model_dump_json().encode()
        count += 1
        while True:
            try:
                connection = connection or await Connection.open(base, headers)
                status = await connection.send(("POST", RUNS, body))
            except (OSError, asyncio.IncompleteReadError, AssertionError, ValueError):
                status = 0
            if status in (200, 201):
                load.stored[str(record.run_id)] = name
                break
            load.retries += 1
            load.station_errors.append((time.monotonic() - t0, status))
            if connection is not None:
                connection.close()
                connection = None
            await asyncio.sleep(RETRY_S)
    if connection is not None:
        connection.close()


async def reader(base: str, until: float, load: Load, t0: float) -> None:
    """Ask for the report until ``until``; note each answer's latency or error."""
    connection: Connection | None = None
    while time.monotonic() < until:
        started = time.monotonic()
        try:
            connection = connection or await Connection.open(base, {})
            status = await connection.send(("GET", EOL, b""))
        except (OSError, asyncio.IncompleteReadError, AssertionError, ValueError):
            status = 0
        if status == 200:
            load.latencies.append(time.monotonic() - started)
            continue
        load.reader_errors.append((time.monotonic() - t0, status))
        if connection is not None:
            connection.close()
            connection = None
        await asyncio.sleep(RETRY_S)
    if connection is not None:
        connection.close()


async def run_load(
    base: str, keys: dict[str, str], readers: int, seconds: float, t0: float
) -> Load:
    load = Load()
    until = time.monotonic() + seconds
    await asyncio.gather(
        *(
            station(base, key, name, i, until, load, t0)
            for i, (name, key) in enumerate(keys.items())
        ),
        *(reader(base, until, load, t0) for _ in range(readers)),
    )
    return load


def load_in_thread(
    base: str, keys: dict[str, str], readers: int, seconds: float, t0: float
) -> tuple[threading.Thread, list[Load]]:
    out: list[Load] = []
    thread = threading.Thread(
        target=lambda: out.append(asyncio.run(run_load(base, keys, readers, seconds, t0)))
    )
    thread.start()
    return thread, out


def percentile(values: list[float], q: float) -> float:
    return float(np.percentile(values, q)) * 1000 if values else float("nan")


def summary(title: str, load: Load, seconds: float) -> None:
    print(
        f"{title}: {len(load.stored) / seconds:.1f} submissions/s ({len(load.stored)} runs, "
        f"{load.retries} retries), report p50 {percentile(load.latencies, 50):.0f} ms "
        f"p95 {percentile(load.latencies, 95):.0f} ms ({len(load.latencies)} reports), "
        f"reader errors {len(load.reader_errors)}"
    )


def seed(url: str, stations: list[str], runs: int) -> dict[str, str]:
    """Migrate the database, store ``runs`` runs of the stations as the server stores
    them (:meth:`RunRepository.submit`), and return a key per station."""
    database = open_database(url, auto_migrate=True)
    rng, np_rng = random.Random(7), np.random.default_rng(7)
    started = time.perf_counter()
    for first in range(0, runs, 100):
        with database.session() as session, session.begin():
            repository = RunRepository(session)
            for index in range(first, min(first + 100, runs)):
                record = new_record(rng, np_rng, index)
                station_id = stations[index % len(stations)]
                repository.submit(record.model_copy(update={"station_id": station_id}))
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        keys = {name: repository.create_key(name) for name in stations}
    database.dispose()
    print(f"seeded {runs:,} runs in {time.perf_counter() - started:.0f} s")
    return keys


def stored_check(url: str, load: Load, before: set[str]) -> tuple[int, int, int]:
    """(runs lost, runs duplicated, runs stored that no station saw stored)."""
    engine = make_engine(url)
    with engine.connect() as connection:
        rows = connection.execute(text("SELECT run_id::text, count(*) FROM runs GROUP BY 1"))
        counts = {run_id: n for run_id, n in rows}
    engine.dispose()
    lost = sum(1 for run_id in load.stored if run_id not in counts)
    duplicated = sum(n - 1 for n in counts.values() if n > 1)
    unseen = len(set(counts) - before - set(load.stored))
    return lost, duplicated, unseen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2_000)
    parser.add_argument("--stations", type=int, default=32)
    parser.add_argument("--readers", type=int, default=60)
    parser.add_argument("--servers", type=int, default=3)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--report-wait-s", type=float, default=120.0)
    parser.add_argument(
        "--replica",
        action="store_true",
        help="a primary and a streaming replica of the benchmark's own (initdb, "
        "pg_basebackup) instead of --postgres-url; the servers read the report from the replica",
    )
    parser.add_argument(
        "--postgres-url", default=os.environ.get("CALSTATION_TEST_POSTGRES_URL", DEFAULT_URL)
    )
    args = parser.parse_args()
    for tool in ("haproxy", "pgbouncer"):
        if shutil.which(tool) is None:
            raise SystemExit(f"{tool} is not installed (apt-get install haproxy pgbouncer)")
    load_before = os.getloadavg()
    failures = []
    with contextlib.ExitStack() as stack:
        replica_server = None
        server_url = args.postgres_url
        if args.replica:
            server_url, replica_server = stack.enter_context(own_cluster())
        url = stack.enter_context(own_database(server_url))
        directory = Path(stack.enter_context(tempfile.TemporaryDirectory()))
        report_url = (
            make_url(replica_server).set(database=make_url(url).database).render_as_string()
            if replica_server
            else None
        )
        names = [f"line{1 + i // 8}-st{1 + i % 8}" for i in range(args.stations)]
        keys = seed(url, names, args.runs)

        # (a) one server, no proxy, PostgreSQL directly.
        port = free_port()
        waiting = {"report_wait_s": str(args.report_wait_s)}
        alone = start_server(url, port, directory, **waiting)
        t0 = time.monotonic()
        baseline = asyncio.run(
            run_load(f"http://127.0.0.1:{port}", keys, args.readers, args.seconds, t0)
        )
        stop(alone)
        summary("one server", baseline, args.seconds)

        # (b) servers behind HAProxy on pgbouncer, one killed and restarted.
        webhook = Webhook()
        rules = webhook.rules(directory, runs=20)
        settings = {
            **waiting,
            # psycopg's prepared statements do not survive transaction pooling in
            # Debian's pgbouncer (1.18; docs/api.md, "Scaling out").
            "prepared_statements": "false",
            "alerts_file": str(rules),
            "alert_interval_s": "1",
            "alert_retry_s": "1",
        }
        if report_url is not None:  # the report from the replica, streamed to directly
            settings["report_database_url"] = report_url
        before = set(stored_run_ids(url))
        with pgbouncer(url) as pooled:
            ports = [free_port() for _ in range(args.servers)]
            servers = [start_server(pooled, each, directory, **settings) for each in ports]
            try:
                sampler = None if report_url is None else LagSampler(server_url, args.seconds)
                with haproxy(ports, directory) as base, sampler or contextlib.nullcontext():
                    t0 = time.monotonic()
                    thread, out = load_in_thread(base, keys, args.readers, args.seconds, t0)
                    time.sleep(args.seconds / 3)
                    killed_at = time.monotonic() - t0
                    servers[0].send_signal(signal.SIGKILL)
                    servers[0].wait()
                    servers[0] = start_server(pooled, ports[0], directory, **settings)
                    back_at = time.monotonic() - t0 + CHECK_MS / 1000
                    thread.join()
                scaled = out[0]
                time.sleep(3)  # the alert loops' next passes
            finally:
                for each in servers:
                    stop(each)
        summary(f"{args.servers} servers behind HAProxy", scaled, args.seconds)
        print(f"server killed at {killed_at:.1f} s, back behind HAProxy by {back_at:.1f} s")
        lost, duplicated, unseen = stored_check(url, scaled, before)
        print(f"runs lost {lost}, duplicated {duplicated}, stored unseen {unseen}")
        inside = [s for t, s in scaled.reader_errors if killed_at <= t <= back_at]
        outside = [s for t, s in scaled.reader_errors if not killed_at <= t <= back_at]
        print(
            f"reader errors during the kill {len(inside)} {sorted(set(inside))}, "
            f"outside it {len(outside)} {sorted(set(outside))}; station errors (retried) "
            f"{len(scaled.station_errors)} {sorted({s for _, s in scaled.station_errors})}"
        )
        if report_url is not None:
            assert sampler is not None
            print(sampler.summary())
            seconds, behind = replica_lag(url, report_url)
            print(f"replica: {behind:,.0f} bytes of WAL behind, replayed in {seconds:.2f} s")
            replicated = set(stored_run_ids(report_url))
            if replicated != set(stored_run_ids(url)):
                failures.append("the replica does not hold the primary's runs")
        posted = webhook.posted
        print(f"alerts posted {len(posted)}: {json.dumps(posted)[:300]}")
        webhook.close()
        if lost or duplicated or unseen:
            failures.append("runs lost, duplicated or unseen")
        if len(posted) != 1:
            failures.append(f"the alert was posted {len(posted)} times, not once")
        if outside and any(s >= 500 for s in outside):
            failures.append("readers saw 5xx outside the kill")
        errors = collections.Counter(
            line.strip()[:160]
            for log in directory.glob("server-*.log")
            for line in log.read_text(errors="replace").splitlines()
            if "Error" in line or "error" in line
        )
        for line, n in errors.most_common(8):
            print(f"server log, {n}x: {line}")
    load_after = os.getloadavg()
    print(f"load average before {load_before[0]:.2f}, after {load_after[0]:.2f} (1 min)")
    if failures:
        raise SystemExit("; ".join(failures))


def stored_run_ids(url: str) -> list[str]:
    engine = make_engine(url)
    with engine.connect() as connection:
        ids = list(connection.scalars(text("SELECT run_id::text FROM runs")))
    engine.dispose()
    return ids


if __name__ == "__main__":
    main()
