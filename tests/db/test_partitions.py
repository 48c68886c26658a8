"""Yearly partitions of ``runs`` and ``poses`` on PostgreSQL (revision 0025,
:mod:`db.partitions`): rows in their year's partition, kept there through the upgrade,
years added ahead, rows of a year created late moved in, reads pruned to their years,
idempotency kept by the register of runs."""

from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest
from sqlalchemy import Connection, func, select, text
from sqlalchemy.orm import Session

from db import RunRepository, make_engine
from db.database import upgrade
from db.models import Run, RunId
from db.partitions import add_years
from db.store.repository import RunConflictError, record_sha256
from tests.conftest import CliRunner
from tests.db.records import make_record
from tests.db.test_migrations import store_at

POSTGRESQL = pytest.mark.parametrize(
    "empty_url", [pytest.param("postgresql", marks=pytest.mark.postgres)], indirect=True
)


def _homes(connection: Connection, table: str) -> dict[int, str]:
    """Each row's partition, by run key."""
    key = "id" if table == "runs" else "run_pk"
    rows = connection.execute(text(f"SELECT {key}, tableoid::regclass::text FROM {table}"))
    return {pk: partition for pk, partition in rows}


def _partitions(connection: Connection) -> set[str]:
    return set(
        connection.scalars(
            text(
                "SELECT inhrelid::regclass::text FROM pg_inherits "
                "WHERE inhparent = 'runs'::regclass"
            )
        )
    )


@POSTGRESQL
def test_the_upgrade_puts_each_run_and_its_poses_in_its_years_partition(
    empty_url: str,
) -> None:
    now = datetime.now(UTC)
    # Two years ago, last year, now, and a station whose clock said 2001.
    starts = [now - timedelta(days=days) for days in (730, 365, 0)] + [
        datetime(2001, 5, 3, tzinfo=UTC)
    ]
    records = [
        make_record(serial=f"PT-00000{i}", started_at=start) for i, start in enumerate(starts)
    ]
    engine = make_engine(empty_url)
    try:
        upgrade(engine, "0024")
        with engine.begin() as connection:
            for record in records:
                store_at(connection, "0024", record, record_sha256(record))
        upgrade(engine)
        with engine.connect() as connection:
            runs, poses = _homes(connection, "runs"), _homes(connection, "poses")
            # The years with runs, this one and the next: not every year from 2001.
            assert _partitions(connection) == {
                *(f"runs_{year}" for year in {s.year for s in starts} | {now.year + 1}),
                "runs_default",
            }
        with Session(engine) as session:
            repository = RunRepository(session)
            for record in records:
                stored = repository.get(record.run_id)
                assert stored is not None
                assert stored.poses == record.poses
                pk = session.scalar(select(RunId.run_pk).where(RunId.run_id == record.run_id))
                assert runs[pk] == f"runs_{record.started_at.year}"
                assert poses[pk] == f"poses_{record.started_at.year}"
            # A retry of a run stored before the upgrade is found, a clash refused, and a
            # new run numbered after the old ones.
            assert not repository.submit(records[0]).created
            with pytest.raises(RunConflictError):
                repository.submit(records[0].model_copy(update={"operator_id": "someone-else"}))
            session.rollback()
            old = session.scalar(select(func.max(Run.id)))
            assert old == len(records)
            assert repository.submit(make_record(serial="PT-000009", started_at=now)).created
            session.commit()
            assert (session.scalar(select(func.max(Run.id))) or 0) > old
    finally:
        engine.dispose()


@POSTGRESQL
def test_runs_outside_the_years_get_a_year_of_their_own(empty_url: str) -> None:
    """A run from before the database's first year (replayed from a station's outbox)
    and one past the year ahead (a clock ahead) wait in the default partition; the job
    gives each its year and moves it in, poses and all."""
    engine = make_engine(empty_url)
    try:
        upgrade(engine)
        now = datetime.now(UTC)
        records = [
            make_record(serial="PT-000001", started_at=datetime(now.year - 3, 6, 1, tzinfo=UTC)),
            make_record(serial="PT-000002", started_at=datetime(now.year + 4, 2, 1, tzinfo=UTC)),
        ]
        with Session(engine) as session:
            for record in records:
                RunRepository(session).submit(record)
            session.commit()
        with engine.connect() as connection:
            assert set(_homes(connection, "runs").values()) == {"runs_default"}
            assert set(_homes(connection, "poses").values()) == {"poses_default"}
        with engine.begin() as connection:
            years = add_years(connection)
        assert years.created == [r.started_at.year for r in records]
        assert years.moved == len(records)
        assert (years.first, years.last) == (now.year - 3, now.year + 4)
        with engine.begin() as connection:
            assert add_years(connection).created == []  # once only
            for table in ("runs", "poses"):
                homes = set(_homes(connection, table).values())
                assert homes == {f"{table}_{r.started_at.year}" for r in records}
            assert add_years(connection, ahead=2).created == [now.year + 2]
        with Session(engine) as session:
            for record in records:
                stored = RunRepository(session).get(record.run_id)
                assert stored is not None
                assert stored.poses == record.poses
    finally:
        engine.dispose()


@POSTGRESQL
def test_a_read_of_one_period_reads_that_years_partitions_only(empty_url: str) -> None:
    """The report's reads of a period and of a run's poses (joined on the run's key and
    start, as :data:`db.rollups.OWN_POSES`): the runs' years are pruned when planned, the
    poses' while executing, run by run."""
    engine = make_engine(empty_url)
    try:
        upgrade(engine)
        start = datetime.now(UTC).replace(month=1, day=1, hour=0, minute=0, second=0)
        with Session(engine) as session:
            RunRepository(session).submit(make_record(started_at=start + timedelta(hours=1)))
            session.commit()
        with engine.connect() as connection:
            plan = (
                connection.execute(
                    text(
                        "EXPLAIN (ANALYZE, COSTS OFF, TIMING OFF, SUMMARY OFF) "
                        "SELECT count(*) FROM runs JOIN poses ON poses.run_pk = runs.id "
                        "AND poses.started_at = runs.started_at "
                        "WHERE runs.started_at >= :start AND runs.started_at < :end"
                    ),
                    {"start": start, "end": start + timedelta(days=1)},
                )
                .scalars()
                .all()
            )
        read = [line for line in plan if " on " in line and "never executed" not in line]
        assert [line.split(" on ")[1].split()[0] for line in read] == [
            f"runs_{start.year}",
            f"poses_{start.year}",
        ], "\n".join(plan)
    finally:
        engine.dispose()


def test_partitions_are_refused_on_sqlite_in_one_line(run_cli: CliRunner, tmp_path: Path) -> None:
    database = tmp_path / "station.sqlite3"
    done = run_cli("db", "partitions", "--database-url", f"sqlite:///{database}")
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        f"calstation: error: database sqlite:///{database} is SQLite: "
        "only PostgreSQL partitions runs by year"
    ]
    assert not database.exists()
