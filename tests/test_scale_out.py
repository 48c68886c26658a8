"""Two servers behind the distribution's HAProxy on pgbouncer, one killed while stations submit.

The smoke version of ``benchmarks/bench_scale_out.py``, with the configuration of
``deploy/scale-out/`` (``.ci/run`` installs haproxy and pgbouncer; without them the test
is skipped and says so). Stations submit their runs through HAProxy, each retrying a run
until it is stored; after the first third of the runs is stored, one server is killed
(SIGKILL) and started again. Every run must then be stored exactly once, and the alert
that the runs fire posted to the webhook once, though every server checks the rules.
And reads through pgbouncer's transaction pooling never fail with the server's prepared
statements off (``CALSTATION_PREPARED_STATEMENTS=false``), and the read timeout
(``CALSTATION_READ_TIMEOUT_S``) holds through it without staying on its pooled connections.
"""

import shutil
import signal
import threading
import time
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from datetime import UTC, datetime, timedelta
from pathlib import Path

import httpx
import pytest
from sqlalchemy import select, text
from sqlalchemy.exc import OperationalError

from db import RunRepository, make_engine, open_database
from db.models import Run
from db.timeouts import is_statement_timeout
from tests.databases import own_postgres_database
from tests.db.records import make_record
from tests.scale_out import HUNG_S, Webhook, haproxy, pgbouncer, start_server, stop
from tests.servers import free_port, local_client

STATIONS = [f"line1-st{i}" for i in range(1, 5)]
RUNS_EACH = 6
#: The alert fires once this many runs are stored, and holds: no ten of the runs' offsets
#: reach a Cpk of 10 (the least spread ten, consecutive in sorted order, have a standard
#: deviation of 15 counts: Cp = 414 / (6 · 15) < 5 against the putter's limits).
ALERT_RUNS = 10

pytestmark = [
    pytest.mark.postgres,
    pytest.mark.skipif(
        shutil.which("haproxy") is None or shutil.which("pgbouncer") is None,
        reason="needs the distribution's haproxy and pgbouncer (apt-get install haproxy "
        "pgbouncer; .ci/run installs them)",
    ),
]


@pytest.fixture
def database_url() -> Iterator[str]:
    """A migrated PostgreSQL database of its own (pgbouncer forwards no search_path)."""
    with own_postgres_database("calstation_scale") as url:
        open_database(url, auto_migrate=True).dispose()
        yield url


def test_runs_are_stored_once_and_the_alert_posted_once_through_a_kill(
    database_url: str, tmp_path: Path
) -> None:
    database = open_database(database_url)
    with database.session() as session, session.begin():
        keys = {name: RunRepository(session).create_key(name) for name in STATIONS}
    webhook = Webhook()
    settings = {
        "prepared_statements": "false",
        "alerts_file": str(webhook.rules(tmp_path, runs=ALERT_RUNS)),
        "alert_interval_s": "0.2",
        "alert_retry_s": "0.2",
    }
    started = datetime.now(UTC) - timedelta(hours=1)
    runs = {
        name: [
            make_record(
                serial=f"SC{s}{i:03d}",
                station_id=name,
                started_at=started + timedelta(minutes=i * len(STATIONS) + s),
                offset=(2030.0 + 3 * ((7 * i + 3 * s) % 41), 2041.2, 1960.5),
            )
            for i in range(RUNS_EACH)
        ]
        for s, name in enumerate(STATIONS)
    }
    stored: list[str] = []
    third = threading.Event()
    lock = threading.Lock()

    def submit(base: str, name: str) -> None:
        headers = {"Authorization": f"Bearer {keys[name]}"}
        with local_client(base) as client:
            for record in runs[name]:
                while True:  # a station sends its run again until it is stored
                    try:
                        answer = client.post(
                            "/api/v1/runs", json=record.model_dump(mode="json"), headers=headers
                        )
                    except httpx.TransportError:
                        continue
                    if answer.status_code in (200, 201):
                        break
                    assert answer.status_code >= 500, answer.text
                with lock:
                    stored.append(str(record.run_id))
                    if len(stored) * 3 >= len(STATIONS) * RUNS_EACH:
                        third.set()

    with pgbouncer(database_url) as pooled:
        ports = [free_port(), free_port()]
        servers = [start_server(pooled, port, tmp_path, **settings) for port in ports]
        try:
            with haproxy(ports, tmp_path) as base, ThreadPoolExecutor(len(STATIONS)) as pool:
                done = [pool.submit(submit, base, name) for name in STATIONS]
                assert third.wait(HUNG_S)
                servers[0].send_signal(signal.SIGKILL)
                servers[0].wait()
                servers[0] = start_server(pooled, ports[0], tmp_path, **settings)
                for each in done:
                    each.result(timeout=HUNG_S)
                with database.engine.connect() as connection:
                    delivered = "SELECT count(*) FROM alerts WHERE delivered_at IS NOT NULL"
                    for _ in range(HUNG_S * 10):
                        if connection.execute(text(delivered)).scalar_one() >= 1:
                            break
                        time.sleep(0.1)  # polled: how soon does not matter
                        connection.rollback()
        finally:
            for server in servers:
                stop(server)
            webhook.close()

    with database.session() as session:
        in_database = [str(run_id) for run_id in session.scalars(select(Run.run_id))]
        alerts = session.execute(text("SELECT count(*) FROM alerts")).scalar_one()
    database.dispose()
    expected = sorted(str(record.run_id) for each in runs.values() for record in each)
    assert sorted(in_database) == expected  # each run once, none lost, none extra
    assert sorted(stored) == expected
    assert alerts == 1
    assert [post["rule"] for post in webhook.posted] == ["cpk"]


def test_reads_through_transaction_pooling_never_fail_without_prepared_statements(
    database_url: str, tmp_path: Path
) -> None:
    # psycopg prepares a statement once it ran five times on a connection; pgbouncer
    # hands the next transaction whichever PostgreSQL connection is free, so concurrent
    # reads (16 at a time, 400 in all) would run a prepared statement where it is not
    # (with CALSTATION_PREPARED_STATEMENTS left true they are answered 500: "prepared
    # statement "_pg3_1" does not exist", or "already exists").
    with pgbouncer(database_url) as pooled:
        port = free_port()
        server = start_server(pooled, port, tmp_path, prepared_statements="false")
        try:
            with local_client(f"http://127.0.0.1:{port}") as client, ThreadPoolExecutor(16) as pool:
                answers = set(
                    pool.map(
                        lambda _: client.get("/api/v1/units/PT-NONE/runs").status_code,
                        range(400),
                    )
                )
        finally:
            stop(server)
    assert answers == {404}  # no such unit, every time: never a 500


#: The read timeout of the tests below (s): a statement waiting on a lock held for the
#: whole request runs past it, whatever the machine's load.
READ_TIMEOUT_S = 0.5


def test_the_read_timeout_holds_through_transaction_pooling_and_stays_in_its_transaction(
    database_url: str,
) -> None:
    # One PostgreSQL connection behind pgbouncer: every transaction below runs on it, so a
    # timeout left on it (a session's SET) would show in the next client's transaction.
    with pgbouncer(database_url, pool_size=1) as pooled:
        timed = make_engine(pooled, statement_timeout_s=READ_TIMEOUT_S)
        plain = make_engine(pooled)
        try:
            with timed.connect() as connection, pytest.raises(OperationalError) as caught:
                connection.execute(text("SELECT pg_sleep(30)"))
            assert is_statement_timeout(caught.value)
            with timed.connect() as connection:  # a short statement passes
                assert connection.execute(text("SELECT pg_sleep(0.01)::text")).scalar_one() == ""
                setting = connection.execute(text("SHOW statement_timeout")).scalar_one()
            assert setting == f"{round(READ_TIMEOUT_S * 1000)}ms"
            with plain.connect() as connection:
                assert connection.execute(text("SHOW statement_timeout")).scalar_one() == "0"
        finally:
            timed.dispose()
            plain.dispose()


def test_a_read_past_the_timeout_through_pgbouncer_answers_503_and_the_next_one_works(
    database_url: str, tmp_path: Path
) -> None:
    # The primary's reads (a unit's runs) and the report (its processes) each wait on a
    # lock held directly on PostgreSQL until their timeout ends them.
    reads = {
        "/api/v1/units/PT-NONE/runs": ("runs", 404),
        "/api/v1/reports/eol": ("report_counts, run_facts", 200),
    }
    database = open_database(database_url)
    with pgbouncer(database_url) as pooled:
        port = free_port()
        server = start_server(
            pooled,
            port,
            tmp_path,
            prepared_statements="false",
            read_timeout_s=str(READ_TIMEOUT_S),
        )
        try:
            with local_client(f"http://127.0.0.1:{port}") as client:
                for path, (tables, answered) in reads.items():
                    with database.engine.connect() as blocker, blocker.begin():
                        blocker.execute(text(f"LOCK TABLE {tables} IN ACCESS EXCLUSIVE MODE"))
                        slow = client.get(path)
                    assert slow.status_code == 503, (path, slow.text)
                    assert slow.json()["detail"].startswith(
                        "the read took longer than the server's read timeout "
                        "(CALSTATION_READ_TIMEOUT_S)"
                    )
                    assert client.get(path).status_code == answered, path
        finally:
            stop(server)
            database.dispose()
