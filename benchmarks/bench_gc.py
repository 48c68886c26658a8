"""The collector's pauses in a results server process, with and without ``gc.freeze()``.

    python benchmarks/bench_gc.py                  # 100,000 runs, about 6 minutes
    python benchmarks/bench_gc.py --runs 20000     # smaller, quicker

Seeds a schema of its own on PostgreSQL as :mod:`bench_api` does (``--postgres-url``,
default ``CALSTATION_TEST_POSTGRES_URL`` or the local ``test`` database). Then, for
``--rounds`` rounds, one server process (uvicorn, the app as ``calstation serve`` builds
it) with the start-up objects frozen as :mod:`api.main` freezes them, and one with them
unfrozen again, in turn: unit lookups at ``--rate`` (default 1,000/s) on 32 connections
while stations submit 10 runs/s on 8 more, for ``--seconds``. Prints per server: the
lookups' p50/p99 and rate, and the collector's pauses in that time (every collection
timed with ``gc.callbacks``): count, the full (generation 2) ones, their longest, the sum.
"""

import argparse
import asyncio
import gc
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import uvicorn
import uvloop
from bench_api import DEFAULT_URL, ROOT, Call, bench_schema, measure, new_record, seed

from api.main import create_app


def serve(port: int, frozen: bool, pauses_out: str) -> None:
    """One server process; writes its collections' ``(generation, seconds)`` at shutdown."""
    pauses: list[tuple[int, float]] = []
    started = [0.0]

    def timed(phase: str, info: dict[str, Any]) -> None:
        if phase == "start":
            started[0] = time.perf_counter()
        else:
            pauses.append((info["generation"], time.perf_counter() - started[0]))

    class Server(uvicorn.Server):
        async def startup(self, sockets: Any = None) -> None:
            await super().startup(sockets)  # the app's start-up freezes what it made
            if not frozen:
                gc.unfreeze()
            pauses.clear()
            gc.callbacks.append(timed)

        async def shutdown(self, sockets: Any = None) -> None:
            gc.callbacks.remove(timed)
            Path(pauses_out).write_text(json.dumps(pauses))
            await super().shutdown(sockets)

    config = uvicorn.Config(create_app(), port=port, log_level="warning", access_log=False)
    Server(config).run()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100_000)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--seconds", type=float, default=15.0)
    parser.add_argument("--rate", type=float, default=1000.0)
    parser.add_argument("--port", type=int, default=8767)
    parser.add_argument("--serve", choices=["frozen", "unfrozen"], help=argparse.SUPPRESS)
    parser.add_argument("--pauses-out", help=argparse.SUPPRESS)
    parser.add_argument(
        "--postgres-url", default=os.environ.get("CALSTATION_TEST_POSTGRES_URL", DEFAULT_URL)
    )
    args = parser.parse_args()
    if args.serve:
        serve(args.port, args.serve == "frozen", args.pauses_out)
        return
    with bench_schema(args.postgres_url) as url, tempfile.TemporaryDirectory() as scratch:
        key, units = seed(url, args.runs)
        np_rng, rng = np.random.default_rng(7), random.Random(7)
        submissions = int(10 * args.seconds * 1.2) + 10
        posts = iter(
            [
                new_record(rng, np_rng, i).model_dump_json().encode()
                for i in range(2 * args.rounds * submissions)
            ]
        )
        stations = {"Authorization": f"Bearer {key}", "Content-Type": "application/json"}

        def lookup(r: random.Random) -> Call:
            return ("GET", f"/api/v1/units/PT-{r.randrange(units):07d}", b"")

        def submit(_: random.Random) -> Call:
            return ("POST", "/api/v1/runs", next(posts))

        print(
            "| start-up objects | round | p50 ms | p99 ms | lookups/s | errors | collections "
            "| full | longest full ms | all pauses ms | load |"
        )
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        for round_ in range(args.rounds):
            order = ("frozen", "unfrozen") if round_ % 2 == 0 else ("unfrozen", "frozen")
            for how in order:
                out = f"{scratch}/{how}-{round_}.json"
                env = {**os.environ, "CALSTATION_DATABASE_URL": url, "PYTHONPATH": str(ROOT)}
                command = [sys.executable, __file__, "--serve", how, "--port", str(args.port)]
                process = subprocess.Popen([*command, "--pauses-out", out], env=env)
                base = f"http://127.0.0.1:{args.port}"
                deadline = time.monotonic() + 60
                while time.monotonic() < deadline:
                    try:
                        if httpx.get(f"{base}/healthz", timeout=1).status_code == 200:
                            break
                    except httpx.TransportError:
                        time.sleep(0.2)

                async def mixed(pid: int, base: str = base) -> Any:
                    return await asyncio.gather(
                        measure(base, pid, 32, args.seconds, lookup, rate=args.rate),
                        measure(
                            base,
                            pid,
                            8,
                            args.seconds,
                            submit,
                            expect=(201,),
                            headers=stations,
                            rate=10,
                        ),
                    )

                looked, submitted = uvloop.run(mixed(process.pid))
                process.terminate()
                process.wait(timeout=30)
                pauses = json.loads(Path(out).read_text())
                full = [s for generation, s in pauses if generation == 2]
                ms = sorted(1e3 * x for x in looked.latencies)
                print(
                    f"| {how} | {round_ + 1} | {statistics.median(ms):.1f} "
                    f"| {ms[int(0.99 * len(ms))]:.1f} | {len(ms) / looked.wall_s:,.0f} "
                    f"| {looked.errors + submitted.errors} | {len(pauses)} | {len(full)} "
                    f"| {1e3 * max(full, default=0.0):.1f} "
                    f"| {1e3 * sum(s for _, s in pauses):.0f} | {os.getloadavg()[0]:.1f} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()
