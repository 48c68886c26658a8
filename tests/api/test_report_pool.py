"""The report pool: a slow or crowded report answers 503 and never holds up anything else.

The statement timeout is produced for real: the test holds a lock the report's first
statement needs (PostgreSQL counts the wait toward ``statement_timeout``), or runs a
statement that never ends on its own.
"""

import subprocess
import sys
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager
from pathlib import Path

import pytest
from sqlalchemy import Connection, text
from sqlalchemy.exc import OperationalError

from api.report_pool import _start
from api.routes import reports
from db import Database, make_engine
from db.timeouts import is_statement_timeout
from tests.conftest import REPO_ROOT
from tests.servers import local_client, serving

EOL = "/api/v1/reports/eol"
POSTGRES_ONLY = pytest.mark.parametrize(
    "database_url", [pytest.param("postgresql", marks=pytest.mark.postgres)], indirect=True
)
ENDLESS = {
    "postgresql": "SELECT pg_sleep(3600)",
    "sqlite": "WITH RECURSIVE c(x) AS (SELECT 1 UNION ALL SELECT x + 1 FROM c) "
    "SELECT max(x) FROM c",
}


def test_a_report_process_imports_no_web_framework() -> None:
    # A report process imports what it unpickles: the pool's initializer and the bodies
    # the report routes hand it. Started from nothing, it must not load FastAPI for them.
    handed = (
        reports.eol_body,
        reports.split_body,
        reports.failing_runs_body,
        reports.dashboard_body,
    )
    modules = sorted({_start.__module__, *(body.__module__ for body in handed)})
    probe = (
        f"import sys, {', '.join(modules)}; "
        "print(sorted({'fastapi', 'starlette', 'uvicorn'} & set(sys.modules)))"
    )
    loaded = subprocess.run(
        [sys.executable, "-c", probe], cwd=REPO_ROOT, capture_output=True, text=True, check=True
    )
    assert loaded.stdout.strip() == "[]", modules


def test_a_report_process_whose_server_is_gone_when_it_starts_ends(tmp_path: Path) -> None:
    # The server process was killed while its report process started: the report
    # process, already left to init, must not wait for a parent it will never lose.
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    url = f"sqlite:///{tmp_path / 'report.db'}"
    started = (
        "import time; from api.report_pool import _start; "
        f"_start({url!r}, 1.0, None, {gone.pid}); time.sleep(3600)"
    )
    report_process = subprocess.Popen([sys.executable, "-c", started], cwd=REPO_ROOT)
    try:
        assert report_process.wait(timeout=120) == 0  # a safety net, not a time measured
    finally:
        report_process.kill()


def test_a_statement_longer_than_the_timeout_is_ended(database_url: str) -> None:
    engine = make_engine(database_url, statement_timeout_s=0.2)
    try:
        with engine.connect() as connection, pytest.raises(OperationalError) as caught:
            connection.execute(text(ENDLESS[engine.dialect.name]))
        assert is_statement_timeout(caught.value)
        with engine.connect() as connection:  # the next statement has its own time
            assert connection.execute(text("SELECT 1")).scalar_one() == 1
    finally:
        engine.dispose()


@contextmanager
def reports_blocked(database: Database) -> Iterator[Connection]:
    """Hold the report's tables locked (a transaction rolled back at the end)."""
    with database.engine.connect() as connection:
        transaction = connection.begin()
        connection.execute(text("LOCK TABLE report_counts, run_facts IN ACCESS EXCLUSIVE MODE"))
        yield connection
        transaction.rollback()


def _waiting_on_a_lock(connection: Connection) -> bool:
    waiting = "SELECT count(*) FROM pg_locks WHERE NOT granted AND relation IS NOT NULL"
    return connection.execute(text(waiting)).scalar_one() > 0


@POSTGRES_ONLY
def test_a_report_past_the_read_timeout_answers_503_and_the_next_one_works(
    database: Database, database_url: str
) -> None:
    with serving(database_url, read_timeout_s="0.5") as base, local_client(base) as client:
        with reports_blocked(database):
            slow = client.get(EOL, timeout=60)
        assert slow.status_code == 503
        assert slow.json()["detail"].startswith(
            "the read took longer than the server's read timeout (CALSTATION_READ_TIMEOUT_S)"
        )
        assert slow.headers["Retry-After"] == "10"
        assert client.get(EOL, timeout=60).status_code == 200


@POSTGRES_ONLY
def test_a_report_that_finds_the_pool_busy_answers_503_and_the_first_one_finishes(
    database: Database, database_url: str
) -> None:
    settings = {"report_pool_size": "1", "report_wait_s": "0.2", "read_timeout_s": "60"}
    with (
        serving(database_url, **settings) as base,
        local_client(base, timeout=60) as client,
        ThreadPoolExecutor(1) as background,
    ):
        with reports_blocked(database) as blocker:
            first = background.submit(client.get, EOL)
            for _ in range(600):  # until the first report waits on the lock (at most 60 s)
                if _waiting_on_a_lock(blocker):
                    break
                assert not first.done(), first.result()
                blocker.execute(text("SELECT pg_sleep(0.1)"))
            assert _waiting_on_a_lock(blocker)
            second = client.get(EOL)
            assert second.status_code == 503
            assert second.json()["detail"] == (
                "every report connection stayed busy for 0.2 s: retry later"
            )
            assert client.get("/healthz").status_code == 200  # other reads go on
        assert first.result(timeout=60).status_code == 200
