"""Where the suite's CPU goes: each test's CPU, its own process's and its processes'.

The suite is bound by the processor (two workers on two cores), so its wall follows its
CPU; ``--durations`` shows wall time, which a busy machine stretches. As a pytest plugin
this module writes, for every test, the CPU of the test process (``time.process_time``)
and of the processes it started and waited for (``RUSAGE_CHILDREN``: servers, stations,
the ``calstation`` commands) into ``$SUITE_CPU_OUT.<pid>.jsonl``; run as a script it adds
them up by file::

    SUITE_CPU_OUT=/tmp/suite-cpu PYTHONPATH=benchmarks python -m pytest -n auto -p suite_cpu
    python benchmarks/suite_cpu.py /tmp/suite-cpu        # the 40 dearest files

A session's shared set-up (the default server, the migrated databases, Chromium) is
counted in the first test that asks for it; a browser's own processes are not waited
for by the test and are not counted.
"""

import argparse
import json
import os
import resource
import time
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path

import pytest

#: Where the plugin writes (one file per test process, ``.<pid>.jsonl`` appended).
OUT_ENV = "SUITE_CPU_OUT"


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item: pytest.Item) -> Iterator[None]:
    """Time one test's set-up, call and tear-down."""
    own, children, wall = time.process_time(), _children_cpu(), time.monotonic()
    yield
    row = {
        "test": item.nodeid,
        "own": time.process_time() - own,
        "children": _children_cpu() - children,
        "wall": time.monotonic() - wall,
    }
    with open(f"{os.environ.get(OUT_ENV, 'suite-cpu')}.{os.getpid()}.jsonl", "a") as out:
        out.write(json.dumps(row) + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description="The suite's CPU by test file.")
    parser.add_argument("prefix", help=f"what {OUT_ENV} was set to")
    parser.add_argument("--top", type=int, default=40, help="files to list")
    args = parser.parse_args()
    prefix = Path(args.prefix)
    rows = [
        json.loads(line)
        for path in prefix.parent.glob(f"{prefix.name}.*.jsonl")
        for line in path.read_text().splitlines()
    ]
    by_file: dict[str, list[float]] = defaultdict(lambda: [0.0, 0.0, 0.0, 0.0])
    for row in rows:
        total = by_file[row["test"].split("::")[0]]
        total[0] += row["own"]
        total[1] += row["children"]
        total[2] += row["wall"]
        total[3] += 1
    own = sum(r["own"] for r in rows)
    children = sum(r["children"] for r in rows)
    print(f"{len(rows)} tests: {own:.0f} s CPU in the test processes, {children:.0f} s in theirs")
    print("| file | tests | CPU | own | processes' | wall |")
    print("|---|---|---|---|---|---|")
    dearest = sorted(by_file.items(), key=lambda item: -(item[1][0] + item[1][1]))
    for name, (o, c, w, n) in dearest[: args.top]:
        print(f"| `{name}` | {n:.0f} | {o + c:.1f} s | {o:.1f} s | {c:.1f} s | {w:.1f} s |")


if __name__ == "__main__":
    main()
