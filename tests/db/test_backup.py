"""``calstation db backup`` and ``calstation db restore`` (real processes; the refusals
in this process) on SQLite and on PostgreSQL (databases of their own, created and
dropped): a database holding runs, units, holds, a review and keys, backed up and
restored into an empty database, holds every row of every table as it was; a restore
into a database that holds tables is refused unless told to replace them."""

from collections.abc import Iterator
from contextlib import ExitStack
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy import inspect, select, text

from db import RunRepository, make_engine, open_database
from db.base import Base
from station.domain.record.records import HoldReview
from tests.conftest import CliRunner
from tests.databases import own_postgres_database
from tests.db.records import OUTCOMES, T0, make_record

Snapshot = dict[str, list[tuple[Any, ...]]]


@pytest.fixture(params=["sqlite", pytest.param("postgresql", marks=pytest.mark.postgres)])
def two_databases(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[tuple[str, str]]:
    """The URLs of two empty databases of the backend: the original and the restored."""
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path / 'line.sqlite3'}", f"sqlite:///{tmp_path / 'restored.sqlite3'}"
        return
    with ExitStack() as stack:
        original = stack.enter_context(own_postgres_database("test_backup"))
        yield original, stack.enter_context(own_postgres_database("test_restore"))


def store_a_line(url: str) -> list[str]:
    """Runs of every outcome over a few units, one held unit reviewed, two keys; the
    keys created."""
    database = open_database(url, auto_migrate=True)
    try:
        with database.session() as session, session.begin():
            repository = RunRepository(session)
            for i, outcome in enumerate(OUTCOMES.values()):
                serial = f"PT-{i % 4:06d}"
                repository.submit(
                    make_record(serial=serial, started_at=T0 + timedelta(hours=i), **outcome)
                )
            held = repository.latest_for_serial("PT-000001")
            assert held is not None
            assert held.verdict == "fail"
            repository.add_review(
                HoldReview(
                    serial="PT-000001",
                    run_id=held.run_id,
                    reviewed_at=T0 + timedelta(days=1),
                    reviewer="qe-ana",
                    root_cause="loose jig",
                    repair_action="jig tightened",
                    decision="retest",
                )
            )
            return [repository.create_key("line1-st1"), repository.create_key("qe-ana", "quality")]
    finally:
        database.dispose()


def snapshot(url: str) -> Snapshot:
    """Every row of every table of the schema (and the schema revision), in key order."""
    engine = make_engine(url)
    try:
        with engine.connect() as connection:
            rows = {
                table.name: [
                    tuple(row)
                    for row in connection.execute(
                        select(table).order_by(*table.primary_key.columns)
                    )
                ]
                for table in Base.metadata.sorted_tables
            }
            rows["alembic_version"] = [
                tuple(row) for row in connection.execute(text("SELECT * FROM alembic_version"))
            ]
            return rows
    finally:
        engine.dispose()


def test_a_backup_restored_into_an_empty_database_holds_every_row(
    two_databases: tuple[str, str], run_cli: CliRunner, tmp_path: Path
) -> None:
    original, restored = two_databases
    keys = store_a_line(original)
    backup = tmp_path / "line.backup"
    done = run_cli("db", "backup", str(backup), "--database-url", original)
    assert done.returncode == 0, done.stderr
    assert backup.stat().st_size > 0
    done = run_cli("db", "restore", str(backup), "--database-url", restored)
    assert done.returncode == 0, done.stderr

    before, after = snapshot(original), snapshot(restored)
    assert len(before["runs"]) == len(OUTCOMES)
    assert before["hold_reviews"]
    assert before["station_keys"]
    assert after == before
    # The restored database serves: its runs read back whole, its keys still open it.
    database = open_database(restored)
    try:
        with database.session() as session:
            repository = RunRepository(session)
            for serial in ("PT-000000", "PT-000001", "PT-000002", "PT-000003"):
                assert repository.history(serial) != []
            assert [repository.key_holder(key) is not None for key in keys] == [True, True]
            assert len(repository.reviews("PT-000001")) == 1
    finally:
        database.dispose()


def test_a_restore_into_a_database_with_tables_is_refused_unless_replaced(
    two_databases: tuple[str, str], run_cli: CliRunner, tmp_path: Path
) -> None:
    original, restored = two_databases
    store_a_line(original)
    # The other database holds a run of its own.
    database = open_database(restored, auto_migrate=True)
    with database.session() as session, session.begin():
        RunRepository(session).submit(make_record(serial="OTHER-1"))
    database.dispose()
    backup = tmp_path / "line.backup"
    assert run_cli("db", "backup", str(backup), "--database-url", original).returncode == 0
    own = snapshot(restored)

    refused = run_cli("db", "restore", str(backup), "--database-url", restored)
    assert refused.returncode == 2
    assert refused.stdout == ""
    assert len(refused.stderr.splitlines()) == 1
    assert "--replace" in refused.stderr
    assert snapshot(restored) == own

    done = run_cli("db", "restore", str(backup), "--replace", "--database-url", restored)
    assert done.returncode == 0, done.stderr
    assert snapshot(restored) == snapshot(original)


def test_bad_backups_and_targets_are_one_line_and_exit_2(
    two_databases: tuple[str, str], call_cli: CliRunner, tmp_path: Path
) -> None:
    original, restored = two_databases
    store_a_line(original)
    backup = tmp_path / "line.backup"
    assert call_cli("db", "backup", str(backup), "--database-url", original).returncode == 0
    not_a_backup = tmp_path / "notes.txt"
    not_a_backup.write_text("not a backup\n")
    cases = {
        "exists: a backup never overwrites": ("backup", str(backup), original),
        "is not a directory": ("backup", str(tmp_path / "none" / "b"), original),
        "no backup at": ("restore", str(tmp_path / "missing"), restored),
        "": ("restore", str(not_a_backup), restored),
    }
    for problem, (command, file, url) in cases.items():
        done = call_cli("db", command, file, "--database-url", url)
        assert done.returncode == 2, (command, file, done.stderr)
        assert len(done.stderr.splitlines()) == 1, done.stderr
        assert problem in done.stderr
        assert "Traceback" not in done.stderr
    # Nothing was restored from what is no backup, and the target is still empty.
    engine = make_engine(restored)
    with engine.connect() as connection:
        assert inspect(connection).get_table_names() == []
    engine.dispose()
