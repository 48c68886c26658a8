"""A short week on the line: ``benchmarks/bench_soak.py`` for one shift, every fault once.

One one-port station and a two-slot fixture send their runs to a real server while the
server is killed and hung, the database drops every connection (PostgreSQL), a
station's disk fills up (where a tmpfs can be mounted), corrupt files land in an outbox
and a key is rotated; then every run must be stored exactly once, no outbox hold
anything, and no request have answered 500 (``docs/benchmarks.md``, *A week on the line*).
"""

import json
import os
import subprocess
import sys

import pytest

from tests.conftest import REPO_ROOT


@pytest.mark.timeout(400)
def test_a_shift_of_every_fault_loses_nothing_and_stores_every_run_once() -> None:
    args = ["--days", "1", "--shifts", "1", "--stations", "1", "--slots", "2", "--units", "2"]
    result = subprocess.run(
        [sys.executable, "benchmarks/bench_soak.py", *args, "--every-fault", "--json"],
        cwd=REPO_ROOT,
        env={**os.environ, "PYTHONPATH": str(REPO_ROOT)},
        capture_output=True,
        text=True,
        timeout=380,
        check=False,
    )
    assert result.stdout, result.stderr[-3000:]
    figures = json.loads(result.stdout)
    assert figures["ok"], figures
    assert result.returncode == 0
    assert figures["runs reported"] == figures["runs stored"] >= 6
    injected = set(figures["faults"])
    assert {"server-kill", "server-hang", "corrupt-file", "key-rotation"} <= injected
    if os.environ.get("CALSTATION_TEST_POSTGRES_URL"):
        assert "database-restart" in injected
