"""The database's size for a plant: bytes per row measured, rows per year modelled.

    python benchmarks/bench_capacity.py                 # 2,000 runs measured, about 2 minutes
    python benchmarks/bench_capacity.py --lines 100 --stations 4 --cycle-s 90

Needs a PostgreSQL server (``--postgres-url``, default ``CALSTATION_TEST_POSTGRES_URL``
or the local ``test`` database). In a database of its own (created and dropped), stores
``--runs`` runs through the submission path (:meth:`db.RunRepository.submit`, as the
server stores them: runs, poses, failures, run facts, roll-ups and the unit's answer),
spread over ``--days`` days and 8 stations, with 3 operators (a shift each) and a lot a
day, then ``VACUUM ANALYZE`` and measures each table's rows and
``pg_total_relation_size`` (heap, TOAST and indexes): its bytes per row.

The model: ``--lines`` lines of ``--stations`` stations, each station finishing a run every
``--cycle-s`` seconds for ``--hours`` hours a day on ``--days-per-year`` days. Runs, poses,
failures and run facts grow with the runs (their rows per run as measured); the roll-ups
(``report_*``) with the station-days (their rows per station-day as measured, the sample
having as many operators and lots a day as the plant's three shifts); the units with the
units made (runs ÷ ``--runs-per-unit``). Prints rows a year, bytes per row and the size
after one and ten years, per table and in all.
"""

import argparse
import os
import random
import time
from datetime import UTC, datetime, timedelta

import numpy as np
from bench_api import DEFAULT_URL, new_record
from bench_scale_out import own_database
from sqlalchemy import text

from db import RunRepository, make_engine, open_database
from db.partitions import is_partition

STATIONS = [f"line1-st{i}" for i in range(1, 9)]
OPERATORS = ["op-a", "op-b", "op-c"]  # one a shift
#: Tables that grow with the runs, and with the station-days.
PER_RUN = ("run_ids", "runs", "poses", "run_failures", "run_facts")
PER_STATION_DAY = ("report_counts", "report_failures", "report_parameters", "report_bounds")


def store(url: str, runs: int, days: int, units: int) -> None:
    """``runs`` runs of ``units`` units over ``days`` days through the submission path."""
    database = open_database(url, auto_migrate=True)
    rng, np_rng = random.Random(5), np.random.default_rng(5)
    start = datetime.now(UTC).replace(hour=0, minute=0, second=0, microsecond=0)
    start -= timedelta(days=days)
    step = timedelta(days=days) / runs
    for first in range(0, runs, 100):
        with database.session() as session, session.begin():
            repository = RunRepository(session)
            for index in range(first, min(first + 100, runs)):
                started = start + index * step
                shift = started.hour * len(OPERATORS) // 24
                record = new_record(rng, np_rng, index).model_copy(
                    update={
                        "serial": f"PN-{index % units:08d}",
                        "station_id": STATIONS[index % len(STATIONS)],
                        "operator_id": OPERATORS[shift],
                        "lot": f"L-{started:%Y%m%d}",
                        "started_at": started,
                        "finished_at": started + timedelta(seconds=95),
                    }
                )
                repository.submit(record)
    database.dispose()


def measure(url: str) -> dict[str, tuple[int, int]]:
    """Each table's rows and total bytes (heap, TOAST, indexes), after VACUUM ANALYZE. A
    partitioned table's bytes are those of its partitions that hold rows: the years
    created ahead, empty, are a fixed cost (their empty indexes), not bytes a row."""
    engine = make_engine(url)
    with engine.connect().execution_options(isolation_level="AUTOCOMMIT") as connection:
        connection.execute(text("VACUUM ANALYZE"))
        tables = connection.scalars(
            text("SELECT tablename FROM pg_tables WHERE schemaname = 'public' ORDER BY 1")
        ).all()
        counted = {
            table: connection.execute(text(f'SELECT count(*) FROM "{table}"')).scalar_one()
            for table in tables
        }
        sizes = {}
        for table in tables:
            if is_partition(table):
                continue
            parts = [p for p in tables if p.startswith(f"{table}_") and is_partition(p)] or [table]
            size = sum(
                connection.execute(
                    text("SELECT pg_total_relation_size(:t)"), {"t": f'public."{part}"'}
                ).scalar_one()
                for part in parts
                if counted[part] or part == table
            )
            sizes[table] = (counted[table], size)
    engine.dispose()
    return sizes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=2_000)
    parser.add_argument("--days", type=int, default=5, help="days the measured runs span")
    parser.add_argument("--lines", type=int, default=100)
    parser.add_argument("--stations", type=int, default=4, help="stations a line")
    parser.add_argument("--cycle-s", type=float, default=90.0)
    parser.add_argument("--hours", type=float, default=20.0, help="working hours a day")
    parser.add_argument("--days-per-year", type=int, default=300)
    parser.add_argument("--runs-per-unit", type=float, default=1.1)
    parser.add_argument("--years", type=int, default=10)
    parser.add_argument(
        "--postgres-url", default=os.environ.get("CALSTATION_TEST_POSTGRES_URL", DEFAULT_URL)
    )
    args = parser.parse_args()
    started = time.perf_counter()
    with own_database(args.postgres_url) as url:
        store(url, args.runs, args.days, max(1, round(args.runs / args.runs_per_unit)))
        sizes = measure(url)
    print(f"measured {args.runs:,} runs in {time.perf_counter() - started:.0f} s")

    stations = args.lines * args.stations
    runs_a_year = stations * args.hours * 3600 / args.cycle_s * args.days_per_year
    station_days_measured = len(STATIONS) * args.days
    station_days_a_year = stations * args.days_per_year
    print(
        f"model: {args.lines} lines x {args.stations} stations, a run every {args.cycle_s:g} s, "
        f"{args.hours:g} h a day, {args.days_per_year} days a year: {runs_a_year:,.0f} runs a year"
    )
    print(
        f"{'table':<20} {'rows measured':>13} {'bytes/row':>9} {'rows a year':>15} "
        f"{'GB a year':>9} {f'GB in {args.years} y':>10}"
    )
    total = 0.0
    for table, (rows, size) in sizes.items():
        if rows == 0:
            continue
        per_row = size / rows
        if table in PER_RUN:
            a_year = rows / args.runs * runs_a_year
        elif table in PER_STATION_DAY:
            a_year = rows / station_days_measured * station_days_a_year
        elif table == "units":
            a_year = runs_a_year / args.runs_per_unit
        else:  # keys, profiles, alerts, outboxes: a few rows, not growing with the runs
            a_year = 0.0
        gigabytes = a_year * per_row / 1e9
        total += gigabytes
        print(
            f"{table:<20} {rows:>13,} {per_row:>9,.0f} {a_year:>15,.0f} "
            f"{gigabytes:>9,.1f} {gigabytes * args.years:>10,.0f}"
        )
    print(f"{'all':<20} {'':>13} {'':>9} {'':>15} {total:>9,.1f} {total * args.years:>10,.0f}")


if __name__ == "__main__":
    main()
