"""Every read of the repository walks an index, in index order: no table scan, no sort."""

import re
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from datetime import timedelta
from typing import Any

import pytest
from sqlalchemy import Connection, event
from sqlalchemy.orm import Session

from db import RunQuery, RunRepository
from tests.db.records import T0, make_record

Statement = tuple[str, Any]


@contextmanager
def captured(connection: Connection) -> Iterator[list[Statement]]:
    """The SQL statements (and parameters) run on ``connection`` inside the block."""
    statements: list[Statement] = []

    def record(_conn: Any, _cursor: Any, sql: str, params: Any, *_: Any) -> None:
        statements.append((sql, params))

    event.listen(connection, "before_cursor_execute", record)
    try:
        yield statements
    finally:
        event.remove(connection, "before_cursor_execute", record)


def _plan(connection: Connection, sql: str, params: Any) -> str:
    if connection.dialect.name == "postgresql":
        # On a few test rows any plan is cheap: forbid the alternatives, so a table
        # scan or a sort only shows when no index can serve the query in order. The
        # statistics are the test's own rows' (ANALYZE in its transaction, rolled back
        # with it), not what other tests last left committed in the shared table: on
        # those a filter on verdict once looked as cheap as its index.
        connection.exec_driver_sql("ANALYZE runs")
        for method in ("seqscan", "bitmapscan", "sort"):
            connection.exec_driver_sql(f"SET LOCAL enable_{method} = off")
        rows = connection.exec_driver_sql(f"EXPLAIN {sql}", params).all()
        return "\n".join(row[0] for row in rows)
    rows = connection.exec_driver_sql(f"EXPLAIN QUERY PLAN {sql}", params).all()
    return "\n".join(row[-1] for row in rows)


READS: dict[str, tuple[Callable[[RunRepository], object], str]] = {
    "latest": (lambda r: r.latest_for_serial("PT-000001"), "ix_runs_serial_started_at"),
    "history": (lambda r: r.history("PT-000001"), "ix_runs_serial_started_at"),
    "by station": (
        lambda r: r.list_runs(RunQuery(station_id="line1-st1", limit=10)),
        "ix_runs_station_id_started_at",
    ),
    "by verdict and time": (
        lambda r: r.list_runs(
            RunQuery(verdict="fail", since=T0, until=T0 + timedelta(days=1), limit=10)
        ),
        "ix_runs_verdict_started_at",
    ),
    "all, newest first": (lambda r: r.list_runs(RunQuery(limit=10)), "ix_runs_started_at"),
}


@pytest.mark.parametrize("read", list(READS))
def test_reads_use_their_index(session: Session, connection: Connection, read: str) -> None:
    repository = RunRepository(session)
    for i in range(3):
        repository.submit(make_record(verdict="fail", started_at=T0 + timedelta(minutes=i)))
    for i in range(30):  # other units, passed at other stations: each read's filter is selective
        repository.submit(
            make_record(
                serial=f"PT-1{i:05d}",
                station_id=f"line1-st{2 + i % 3}",
                started_at=T0 + timedelta(minutes=3 + i),
            )
        )
    session.flush()
    query, index = READS[read]
    with captured(connection) as statements:
        query(repository)
    runs_sql = [(sql, p) for sql, p in statements if "FROM runs" in sql]
    assert runs_sql, statements
    plan = _plan(connection, *runs_sql[0])
    if connection.dialect.name == "postgresql":
        # Partitioned by year: the partition that holds the test's runs walks its copy of
        # the index, named after the index's columns; the years merge in order (a Merge
        # Append, no Sort).
        (partition,) = connection.exec_driver_sql(
            "SELECT DISTINCT tableoid::regclass::text FROM runs"
        ).scalars()
        index = f"{partition}_{index.removeprefix('ix_runs_')}_id_idx"
    assert index in plan, plan
    assert "Seq Scan" not in plan, plan
    assert not re.search(r"SCAN runs(?! USING (COVERING )?INDEX)", plan), plan
    assert not re.search(r"\bSort\b(?! Key)", plan), plan
    assert "TEMP B-TREE" not in plan, plan
