"""``calstation db upgrade`` and ``calstation keys create`` through their entry point in
the test's process (``call_cli``)."""

import os
from datetime import timedelta
from pathlib import Path

import pytest
from sqlalchemy import delete, func, select

from db import Database, RunRepository, make_engine
from db.database import upgrade
from db.migrate import HEAD_REVISION
from db.models import ReportCounts, StationKey
from db.store.repository import KeyHolder
from tests.conftest import CliRunner
from tests.db.records import T0, make_record

#: A schema revision before the head.
OLDER = f"{int(HEAD_REVISION) - 2:04d}"
UNREACHABLE = "postgresql+psycopg://nobody@127.0.0.1:1/none?connect_timeout=2"


def _env(**variables: str) -> dict[str, str]:
    clean = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    return {**clean, **variables}


def test_db_upgrade_creates_the_embedded_database_in_the_data_dir(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    result = call_cli("db", "upgrade", env=_env(CALSTATION_DATA_DIR=str(tmp_path / "data")))
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "data" / "calstation.sqlite3").is_file()
    assert f"created at schema revision {HEAD_REVISION}\n" in result.stdout


def test_db_upgrade_is_idempotent_on_a_migrated_database(
    call_cli: CliRunner, migrated_database: Database, database_url: str
) -> None:
    result = call_cli("db", "upgrade", "--database-url", database_url, env=_env())
    assert result.returncode == 0, result.stderr
    assert f"already at schema revision {HEAD_REVISION}: nothing to migrate" in result.stdout


def test_db_upgrade_says_from_which_revision_it_migrated(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    url = f"sqlite:///{tmp_path / 'old.sqlite3'}"
    engine = make_engine(url)
    upgrade(engine, OLDER)
    engine.dispose()
    result = run_cli("db", "upgrade", "--database-url", url, env=_env())
    assert result.returncode == 0, result.stderr
    said = f"database {url} migrated from schema revision {OLDER} to {HEAD_REVISION}\n"
    assert result.stdout == said


def test_an_unreachable_database_is_one_line_and_exit_2(call_cli: CliRunner) -> None:
    for command in (("db", "upgrade"), ("keys", "create", "--station", "st1"), ("serve",)):
        result = call_cli(*command, "--database-url", UNREACHABLE, env=_env())
        assert result.returncode == 2, (command, result.stderr)
        assert result.stderr.startswith("calstation: error: ")
        assert "unavailable" in result.stderr
        assert "Traceback" not in result.stderr
        assert "nobody@127.0.0.1" in result.stderr
        assert len(result.stderr.strip().splitlines()) == 1


def test_keys_create_prints_a_key_stored_only_as_its_hash(
    call_cli: CliRunner, database: Database, database_url: str
) -> None:
    result = call_cli(
        "keys", "create", "--station", "line3-st2", "--database-url", database_url, env=_env()
    )
    assert result.returncode == 0, result.stderr
    key = result.stdout.strip()
    assert key.startswith("csk_")
    assert "line3-st2" in result.stderr
    with database.session() as session:
        assert RunRepository(session).key_holder(key) == KeyHolder("line3-st2", "station")
        assert key not in session.scalars(select(StationKey.key_sha256)).one()


def test_keys_create_refuses_a_bad_station_id(call_cli: CliRunner, tmp_path: Path) -> None:
    result = call_cli(
        "keys", "create", "--station", "line 3", env=_env(CALSTATION_DATA_DIR=str(tmp_path))
    )
    assert result.returncode == 2
    assert "--station" in result.stderr


def test_keys_create_lab_makes_a_key_for_gyro_fits(
    call_cli: CliRunner, database: Database, database_url: str
) -> None:
    result = call_cli(
        "keys", "create", "--lab", "gyro-lab", "--database-url", database_url, env=_env()
    )
    assert result.returncode == 0, result.stderr
    assert "lab gyro-lab" in result.stderr
    with database.session() as session:
        assert RunRepository(session).key_holder(result.stdout.strip()) == KeyHolder(
            "gyro-lab", "lab"
        )
    revoked = call_cli(
        "keys", "revoke", "--lab", "gyro-lab", "--database-url", database_url, env=_env()
    )
    assert "revoked 1 API key of lab gyro-lab" in revoked.stdout


@pytest.mark.parametrize(
    "given", [[], ["--station", "line3-st2", "--lab", "gyro-lab"]], ids=["neither", "both"]
)
def test_keys_create_needs_exactly_one_holder(
    call_cli: CliRunner, tmp_path: Path, given: list[str]
) -> None:
    result = call_cli("keys", "create", *given, env=_env(CALSTATION_DATA_DIR=str(tmp_path)))
    assert result.returncode == 2
    assert "--station/--lab/--quality: name one holder" in result.stderr
    assert "Traceback" not in result.stderr
    assert not (tmp_path / "calstation.sqlite3").exists()


def test_keys_revoke_stops_every_key_of_the_station(
    call_cli: CliRunner, database: Database, database_url: str
) -> None:
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        keys = [repository.create_key("line3-st2") for _ in range(2)]
        other = repository.create_key("line3-st3")
    result = call_cli(
        "keys", "revoke", "--station", "line3-st2", "--database-url", database_url, env=_env()
    )
    assert result.returncode == 0, result.stderr
    assert "revoked 2 API keys" in result.stdout
    with database.session() as session:
        repository = RunRepository(session)
        assert [repository.key_holder(key) for key in keys] == [None, None]
        assert repository.key_holder(other) == KeyHolder("line3-st3", "station")


def test_db_rebuild_report_restores_the_roll_ups_from_the_runs(
    call_cli: CliRunner, database: Database, database_url: str
) -> None:
    with database.session() as session:
        for minute in range(3):
            RunRepository(session).submit(
                make_record(serial=f"U{minute}", started_at=T0 + timedelta(minutes=minute))
            )
        session.execute(delete(ReportCounts))
        session.commit()
    result = call_cli("db", "rebuild-report", "--database-url", database_url, env=_env())
    assert result.returncode == 0, result.stderr
    assert "rebuilt from 3 runs, parameters binned against kxm52-production" in result.stdout
    with database.session() as session:
        assert session.scalar(select(func.sum(ReportCounts.runs))) == 3
