"""Report readers beside submissions: do key-less reads starve the stations?

    python benchmarks/bench_readers.py                  # 100,000 runs, about 2 minutes
    python benchmarks/bench_readers.py --runs 20000     # smaller, quicker

A real ``calstation serve`` (``--workers``, default 2) on PostgreSQL (``--postgres-url``,
default ``CALSTATION_TEST_POSTGRES_URL`` or the local ``test`` database), in a schema of
its own seeded as :mod:`bench_api` seeds it and dropped at the end. Measures:
(a) ``POST /api/v1/runs`` from ``--stations`` stations (default 8), each sending its next
    run as soon as the last is answered, alone;
(b) the same while ``--readers`` clients (default 60) ask for the end-of-line report
    (``GET /api/v1/reports/eol``, JSON, the whole range) as fast as they are answered.
Target: submissions/s in (b) at least half of (a). A reader answered 503 (its report
timed out, or every report connection stayed busy) counts as an error of the readers.
"""

import argparse
import asyncio
import os
import random

import numpy as np
import uvloop
from bench_api import (
    DEFAULT_URL,
    Call,
    Result,
    bench_schema,
    measure,
    new_record,
    seed,
    server,
)

EOL = "/api/v1/reports/eol"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100_000)
    parser.add_argument("--stations", type=int, default=8)
    parser.add_argument("--readers", type=int, default=60)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--port", type=int, default=8766)
    parser.add_argument(
        "--postgres-url", default=os.environ.get("CALSTATION_TEST_POSTGRES_URL", DEFAULT_URL)
    )
    args = parser.parse_args()
    load_before = os.getloadavg()

    with bench_schema(args.postgres_url) as url:
        key, _units = seed(url, args.runs)
        np_rng, rng = np.random.default_rng(11), random.Random(11)
        posts = iter([new_record(rng, np_rng, i).model_dump_json().encode() for i in range(5_000)])
        stations = {"Authorization": f"Bearer {key}", "Content-Type": "application/json"}

        def submit(_: random.Random) -> Call:
            return ("POST", "/api/v1/runs", next(posts))

        def report(_: random.Random) -> Call:
            return ("GET", EOL, b"")

        with server(url, args.workers, args.port) as (base, pid):

            async def submissions() -> Result:
                return await measure(
                    base, pid, args.stations, args.seconds, submit, (201,), headers=stations
                )

            async def beside_readers() -> tuple[Result, Result]:
                return await asyncio.gather(
                    submissions(), measure(base, pid, args.readers, args.seconds, report)
                )

            uvloop.run(measure(base, pid, 4, 3.0, report))  # warm-up: plans, pools
            alone = uvloop.run(submissions())
            beside, readers = uvloop.run(beside_readers())
            beside, readers = beside.together(readers)

    ratio = (len(alone.latencies) / alone.wall_s) / max(1e-9, len(beside.latencies) / beside.wall_s)
    print()
    print(f"{args.runs:,} runs seeded; server: {args.workers} uvicorn workers")
    print(f"load average before the run: {load_before}; after: {os.getloadavg()}")
    print()
    print(
        "| request | clients | requests | p50 ms | p99 ms | per s "
        "| server CPU ms/req | client CPU ms/req | errors |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    print(alone.row("POST /api/v1/runs, alone", args.stations))
    print(beside.row(f"POST /api/v1/runs, beside {args.readers} report readers", args.stations))
    print(readers.row(f"GET {EOL}, beside the stations", args.readers))
    print()
    print(f"submissions/s alone ÷ beside the readers: {ratio:.2f} (target ≤ 2)")


if __name__ == "__main__":
    main()
