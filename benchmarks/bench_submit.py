"""One submission's cost in the server's own process: ``RunRepository.submit``, timed.

    python benchmarks/bench_submit.py                   # 100,000 runs seeded, about 2 minutes
    python benchmarks/bench_submit.py --runs 20000      # smaller, quicker
    python benchmarks/bench_submit.py --years-ahead 9    # with ten years of partitions

Seeds a schema of its own on PostgreSQL as :mod:`bench_api` does (``--postgres-url``,
default ``CALSTATION_TEST_POSTGRES_URL`` or the local ``test`` database), then stores
``--submissions`` runs of each kind, one transaction each, in this process, as the API's
submission does (validation and the HTTP layer aside): a new unit's first run; a retest
of a seeded unit (its runs before it); a run delivered late (started before the unit's
latest stored run). The first ``--warmup`` submissions, which compile SQLAlchemy's
statements, are not counted. Prints per kind the median and 90th percentile of the CPU
time of this process (``time.process_time``) and of the wall time per submission.
``--years-ahead N`` first gives ``runs`` and ``poses`` N years of partitions past the
current one (:func:`db.partitions.add_years`; the migration makes one): a database that
keeps ten years plans and reads that many partitions where it looks a unit up by serial
(``--years-ahead 119`` stands for ten years of months).
"""

import argparse
import os
import random
import statistics
import time
from datetime import timedelta

import numpy as np
from bench_api import DEFAULT_URL, T0, bench_schema, new_record, seed

from db import RunRepository, open_database
from db.partitions import add_years
from station.domain.record.records import RunRecord


def records(kind: str, count: int, units: int) -> list[RunRecord]:
    """``count`` runs of one kind (``new``, ``retest``, ``late``)."""
    rng, np_rng = random.Random(kind), np.random.default_rng(len(kind))
    made = []
    for i in range(count):
        record = new_record(rng, np_rng, i)
        if kind != "new":
            serial = f"PT-{rng.randrange(units):07d}"
            # Seeded runs start from T0 on, new ones now: a late run goes before them all.
            started = T0 - timedelta(seconds=i) if kind == "late" else record.started_at
            record = record.model_copy(
                update={
                    "serial": serial,
                    "started_at": started,
                    "finished_at": started + timedelta(seconds=95),
                }
            )
        made.append(record)
    return made


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100_000)
    parser.add_argument("--submissions", type=int, default=300)
    parser.add_argument("--warmup", type=int, default=20)
    parser.add_argument("--years-ahead", type=int, default=1)
    parser.add_argument(
        "--postgres-url", default=os.environ.get("CALSTATION_TEST_POSTGRES_URL", DEFAULT_URL)
    )
    args = parser.parse_args()
    load_before = os.getloadavg()
    rows = []
    with bench_schema(args.postgres_url) as url:
        _key, units = seed(url, args.runs)
        database = open_database(url)
        with database.engine.begin() as connection:
            years = add_years(connection, args.years_ahead)
        for kind in ("new", "retest", "late"):
            cpu, wall = [], []
            for i, record in enumerate(records(kind, args.warmup + args.submissions, units)):
                wall0, cpu0 = time.perf_counter(), time.process_time()
                with database.session() as session, session.begin():
                    assert RunRepository(session).submit(record).created
                if i >= args.warmup:
                    cpu.append(1e3 * (time.process_time() - cpu0))
                    wall.append(1e3 * (time.perf_counter() - wall0))
            rows.append((kind, cpu, wall))
        database.dispose()

    def p90(values: list[float]) -> float:
        return statistics.quantiles(values, n=10)[-1]

    after = os.getloadavg()
    print(f"\n{args.runs:,} runs seeded; load average before: {load_before}, after: {after}")
    print(f"runs and poses partitioned by year from {years.first} to {years.last}\n")
    print("| submission | n | CPU ms median | CPU ms p90 | wall ms median | wall ms p90 |")
    print("|---|---|---|---|---|---|")
    for kind, cpu, wall in rows:
        print(
            f"| {kind} | {len(cpu)} | {statistics.median(cpu):.2f} | {p90(cpu):.2f} "
            f"| {statistics.median(wall):.2f} | {p90(wall):.2f} |"
        )


if __name__ == "__main__":
    main()
