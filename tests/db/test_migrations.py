"""Migrations: an empty database reaches head matching the models; SQLite needs no set-up."""

import ast
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
from alembic import command
from alembic.autogenerate import compare_metadata
from alembic.runtime.migration import MigrationContext
from alembic.script import ScriptDirectory
from sqlalchemy import Connection, func, insert, inspect, select, text
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

import db.migrations
from db import (
    Database,
    DatabaseSettings,
    RunRepository,
    SchemaOutOfDateError,
    make_engine,
    open_database,
    upgrade_database,
)
from db.base import Base
from db.database import upgrade
from db.migrate import HEAD_REVISION, alembic_config, current_revision
from db.models import (
    ReportCounts,
    Run,
    RunFacts,
    RunFailure,
    RunPose,
    StoredLimitsProfile,
    Unit,
)
from db.partitions import include_name
from db.report.reports import eol_report
from db.store.mapping import failure_rows, pose_row, run_row
from db.store.repository import KeyHolder, key_sha256, record_sha256
from db.store.units import answer_json
from station.domain.quality.figures import ReportFilter
from station.domain.record.records import RunRecord
from station.domain.record.signature import (
    SignatureMismatchError,
    SignedCertificate,
    canonical_record,
    load_private_key,
    new_key,
    sign,
    station_record,
    verify,
)
from station.report.certificate import document_number
from station.report.html import certificate_page
from tests.db.records import LIMITS, T0, make_record
from tests.db.test_rollups import rollup_rows


def scripts_head() -> str:
    """The newest revision of the packaged migrations, as Alembic reads the scripts."""
    head = ScriptDirectory.from_config(alembic_config()).get_current_head()
    assert head is not None, "the packaged migrations have no head"
    return head


def _before_0016(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """Failure rows as a database before revision 0016 holds them (no ``uncertainty``)."""
    return [{k: v for k, v in row.items() if k != "uncertainty"} for row in rows]


#: The revision that added each column of ``runs`` after 0003.
_ADDED = {
    "disposition": "0006",
    "gyro_matrix": "0008",
    "purpose": "0009",
    "excluded_poses": "0010",
    "uncertainty": "0013",
    "decision_rule": "0013",
    "part_number": "0014",
    "fixture_slot": "0015",
    "as_found": "0022",
    "check_rules": "0024",
}


def store_at(
    connection: Connection, revision: str, record: RunRecord, digest: str = "0" * 64
) -> None:
    """Store ``record`` with its poses and failures as a database at ``revision`` (at
    least 0003, before 0025) holds them: the columns added later left out."""
    pk = connection.scalar(select(func.coalesce(func.max(Run.id), 0) + 1))
    row = run_row(record, pk=pk, received_at=T0, record_sha256=digest)
    kept = {name: value for name, value in row.items() if _ADDED.get(name, revision) <= revision}
    connection.execute(insert(Run), kept)
    poses = [pose_row(pk, record.started_at, pose) for pose in record.poses]
    for pose in poses:
        del pose["started_at"]  # a column of revision 0025
    connection.execute(insert(RunPose), poses)
    if record.failures:
        failures = failure_rows(pk, record)
        connection.execute(
            insert(RunFailure), failures if revision >= "0016" else _before_0016(failures)
        )


def test_head_matches_the_models_with_no_autogenerate_diff(empty_url: str) -> None:
    engine = make_engine(empty_url)
    upgrade(engine)
    with engine.connect() as connection:
        context = MigrationContext.configure(
            connection, opts={"compare_type": True, "include_name": include_name}
        )
        diff = compare_metadata(context, Base.metadata)
    engine.dispose()
    assert diff == []


def test_downgrade_to_base_and_back_up(empty_url: str) -> None:
    engine = make_engine(empty_url)
    upgrade(engine)
    with engine.begin() as connection:
        command.downgrade(alembic_config(connection), "base")
    assert set(inspect(engine).get_table_names()) <= {"alembic_version"}
    upgrade(engine)
    assert current_revision(engine) == scripts_head()
    engine.dispose()


def test_the_head_opening_checks_against_is_the_one_the_packaged_scripts_reach() -> None:
    assert scripts_head() == HEAD_REVISION


def test_the_embedded_database_is_created_and_migrated_on_first_use(tmp_path: Path) -> None:
    settings = DatabaseSettings(database_url=None, data_dir=tmp_path / "nested" / "data")
    database = open_database(settings.url())
    assert (tmp_path / "nested" / "data" / "calstation.sqlite3").is_file()
    assert current_revision(database.engine) == scripts_head()
    database.dispose()


@pytest.mark.parametrize(
    "empty_url", [pytest.param("postgresql", marks=pytest.mark.postgres)], indirect=True
)
def test_a_server_database_behind_head_is_refused_with_the_fix(empty_url: str) -> None:
    with pytest.raises(SchemaOutOfDateError, match="calstation db upgrade"):
        open_database(empty_url)


def test_the_units_migration_fills_each_units_current_state(empty_url: str) -> None:
    engine = make_engine(empty_url)
    upgrade(engine, "0003")
    first = make_record(verdict="fail", started_at=T0)
    retest = make_record(verdict="pass", started_at=T0 + timedelta(hours=1))
    other = make_record(serial="PT-000002", started_at=T0 + timedelta(hours=2))
    with engine.begin() as connection:  # runs stored before the units table existed
        for record in (retest, first, other):
            store_at(connection, "0003", record)
    upgrade(engine)
    database = Database(engine)
    with database.session() as session:
        repo = RunRepository(session)
        stored = {s: c for s, c in session.execute(select(Unit.serial, Unit.calibration))}
        expected = {serial: answer_json(repo.history(serial)) for serial in stored}
    assert stored == expected
    assert set(stored) == {"PT-000001", "PT-000002"}
    assert f'"run_id":"{retest.run_id}"' in stored["PT-000001"]
    engine.dispose()


def test_the_report_migration_builds_the_roll_ups_of_the_runs_already_stored(
    empty_url: str,
) -> None:
    engine = make_engine(empty_url)
    try:
        upgrade(engine)
        with Session(engine) as session:
            for hour, serial in enumerate(["U1", "U2", "U1"]):
                RunRepository(session).submit(
                    make_record(serial=serial, started_at=T0 + timedelta(hours=hour))
                )
            session.commit()
            submitted = rollup_rows(session)
        with engine.begin() as connection:
            command.downgrade(alembic_config(connection), "0002")
        assert "run_facts" not in inspect(engine).get_table_names()
        upgrade(engine)
        with Session(engine) as session:
            assert rollup_rows(session) == submitted
            assert session.scalar(select(func.sum(ReportCounts.poses))) == 3 * 7
    finally:
        engine.dispose()


def test_the_product_migration_rebuilds_the_roll_ups_per_part_number(empty_url: str) -> None:
    """Revision 0019 keys the roll-ups by part number too: from 0016, whose roll-ups have
    no product, the upgrade writes them anew from the runs, one row per product."""
    engine = make_engine(empty_url)
    try:
        upgrade(engine)
        with Session(engine) as session:
            for hour, (serial, product) in enumerate(
                [("U1", "DIXX-A12"), ("U2", "DIXX-D16"), ("U1", "DIXX-A12"), ("U3", "DIXX-D16")]
            ):
                RunRepository(session).submit(
                    make_record(
                        serial=serial, part_number=product, started_at=T0 + timedelta(hours=hour)
                    )
                )
            session.commit()
            submitted = rollup_rows(session)
        with engine.begin() as connection:
            command.downgrade(alembic_config(connection), "0016")
        for table in ("report_counts", "report_failures", "report_parameters"):
            assert "part_number" not in {c["name"] for c in inspect(engine).get_columns(table)}
        upgrade(engine)
        with Session(engine) as session:
            assert rollup_rows(session) == submitted
            runs = select(ReportCounts.part_number, func.sum(ReportCounts.runs))
            by_product = session.execute(runs.group_by(ReportCounts.part_number)).all()
            assert sorted(by_product) == [("DIXX-A12", 2), ("DIXX-D16", 2)]
    finally:
        engine.dispose()


def test_the_yield_migration_recounts_attempts_retests_and_aborts(empty_url: str) -> None:
    """Revision 0021 counts attempts: from 0020, whose facts took an aborted first run for
    the unit's first, the upgrade writes the facts and roll-ups anew, and U1 (aborted at
    st1, passed at st2) is first-pass at st2 with no retest; U2's retest is st2's."""
    engine = make_engine(empty_url)
    plan = [
        ("U1", "st1", [{"code": "aborted", "message": "aborted by the operator"}]),
        ("U1", "st2", []),
        ("U2", "st1", [{"code": "offset", "message": "out of limits"}]),
        ("U2", "st2", []),
    ]
    try:
        upgrade(engine)
        with Session(engine) as session:
            for hour, (serial, station, failures) in enumerate(plan):
                RunRepository(session).submit(
                    make_record(
                        serial=serial,
                        station_id=station,
                        verdict="fail" if failures else "pass",
                        failures=failures,
                        started_at=T0 + timedelta(hours=hour),
                    )
                )
            session.commit()
            submitted = rollup_rows(session)
        with engine.begin() as connection:
            command.downgrade(alembic_config(connection), "0020")
        assert "attempt" not in {c["name"] for c in inspect(engine).get_columns("run_facts")}
        upgrade(engine)
        with Session(engine) as session:
            assert rollup_rows(session) == submitted
            report = eol_report(session, ReportFilter())
            rows = {s.station_id: s.summary for s in report.stations}
            st1, st2 = rows["st1"], rows["st2"]
            assert (st1.units_tested, st1.retests, st1.aborted_runs) == (1, 0, 1)
            assert (st2.units_tested, st2.first_pass_units, st2.retests) == (1, 1, 1)
    finally:
        engine.dispose()


def test_the_key_scope_migration_makes_every_existing_key_a_station_key(empty_url: str) -> None:
    engine = make_engine(empty_url)
    upgrade(engine, "0004")
    with engine.begin() as connection:  # a key created before keys had a scope
        connection.execute(
            text(
                "INSERT INTO station_keys (station_id, key_sha256, created_at) "
                "VALUES ('line1-st1', :digest, :now)"
            ),
            {"digest": key_sha256("csk_old"), "now": T0},
        )
    upgrade(engine)
    with Database(engine).session() as session:
        assert RunRepository(session).key_holder("csk_old") == KeyHolder("line1-st1", "station")
    with engine.begin() as connection, pytest.raises(IntegrityError):
        connection.execute(text("UPDATE station_keys SET scope = 'admin'"))
    engine.dispose()


def test_the_disposition_migration_keeps_every_row_of_every_run(empty_url: str) -> None:
    engine = make_engine(empty_url)
    try:
        upgrade(engine, "0005")
        record = make_record(verdict="fail")
        with engine.begin() as connection:  # a run stored before runs had a disposition
            store_at(connection, "0005", record)
        upgrade(engine)
        with Session(engine) as session:
            (stored,) = RunRepository(session).history(record.serial)
            assert stored.disposition is None
            assert stored.fixture_slot is None  # never guessed (revision 0015)
            assert stored.failures == record.failures
            assert session.scalar(select(func.count()).select_from(RunFailure)) == 1
    finally:
        engine.dispose()


def test_runs_from_before_as_found_say_not_recorded(empty_url: str) -> None:
    """Revision 0022 adds ``runs.as_found``; a run stored before it has none: its
    record reads back without it and its certificate says "not recorded"."""
    engine = make_engine(empty_url)
    try:
        upgrade(engine, "0021")
        record = make_record()
        with engine.begin() as connection:
            store_at(connection, "0021", record, record_sha256(record))
        upgrade(engine)
        with Session(engine) as session:
            stored = RunRepository(session).get(record.run_id)
        assert stored is not None
        assert stored.as_found is None
        page = certificate_page(stored, None, T0)
        assert '<p class="as-found">as found: not recorded</p>' in page
    finally:
        engine.dispose()


def test_a_guarded_run_from_before_check_rules_keeps_its_rules_and_its_signature(
    empty_url: str,
) -> None:
    """Revision 0024 adds ``runs.check_rules``; a guarded run stored before it guarded
    its offsets, sensitivities and gyro biases only and judged K and the verification
    error by their values: read back, its record says so, and its signature (over the
    record as signed then) still verifies."""
    engine = make_engine(empty_url)
    try:
        upgrade(engine, "0023")
        # As the server holds it (its limits profile stored apart) and a signatory signs it.
        reference = {key: value for key, value in LIMITS.items() if key != "profile"}
        record = make_record(decision_rule="guarded", limits=reference)
        assert record.check_rules is None
        pem, public = new_key()
        key = load_private_key(pem, "key.pem")
        signature = sign(record, document_number(record), "alice", key, T0)
        with engine.begin() as connection:
            store_at(connection, "0023", record, record_sha256(record))
        upgrade(engine)
        with Session(engine) as session:
            stored = RunRepository(session).get(record.run_id)
        assert stored is not None
        assert stored.check_rules is None
        assert [stored.rule_of(c) for c in ("offset", "sensitivity", "gyro_bias")] == [
            "guarded"
        ] * 3
        for code in ("gyro_scale", "gyro_misalignment", "verification_error", "pose_noise"):
            assert stored.rule_of(code) == "simple"
        assert "check_rules" not in canonical_record(station_record(stored)).decode()
        verify(SignedCertificate(record=station_record(stored), signature=signature), public)
        # One digit changed in the record still fails: the check can fail.
        changed = station_record(stored).model_copy(update={"decision_rule": "simple"})
        with pytest.raises(SignatureMismatchError):
            verify(SignedCertificate(record=changed, signature=signature), public)
    finally:
        engine.dispose()


#: Top-level packages of this project: a revision that imports one of them would create
#: something else whenever that code is edited.
PROJECT_PACKAGES = {"station", "api", "db", "tests", "benchmarks"}


def _imported_packages(source: str) -> set[str]:
    """The top-level packages a module's source imports, wherever in its code."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            names.add(node.module or "")
    return {name.split(".")[0] for name in names}


def test_no_revision_imports_project_code() -> None:
    versions = sorted((Path(db.migrations.__file__).parent / "versions").glob("*.py"))
    assert versions
    for path in versions:
        imported = _imported_packages(path.read_text(encoding="utf-8"))
        assert imported & PROJECT_PACKAGES == set(), path.name


def _execute(url: str, sql: str) -> None:
    """Run one statement on the database at ``url``, committed."""
    engine = make_engine(url)
    with engine.begin() as connection:
        connection.execute(text(sql))
    engine.dispose()


def test_a_database_written_by_a_newer_calstation_is_refused_in_one_line(
    tmp_path: Path,
) -> None:
    url = f"sqlite:///{tmp_path / 'newer.sqlite3'}"
    open_database(url).dispose()
    _execute(url, "UPDATE alembic_version SET version_num = 'ffffffffffff'")
    with pytest.raises(SchemaOutOfDateError, match=r"ffffffffffff.*newer calstation"):
        open_database(url)


@pytest.mark.parametrize(
    "empty_url", [pytest.param("postgresql", marks=pytest.mark.postgres)], indirect=True
)
def test_a_server_database_with_the_head_and_another_revision_is_refused(
    empty_url: str,
) -> None:
    upgrade_database(empty_url)
    _execute(empty_url, "INSERT INTO alembic_version (version_num) VALUES ('0019')")
    with pytest.raises(SchemaOutOfDateError, match=rf"revision 0019, {HEAD_REVISION}, this"):
        open_database(empty_url)


def test_runs_from_before_stored_profiles_keep_the_report_working(empty_url: str) -> None:
    """The shipped profile those runs used is stored by the migration; another one stays
    unknown: the report then measures against the bounds the roll-ups were counted with."""
    engine = make_engine(empty_url)
    try:
        upgrade(engine, "0006")
        shipped = make_record(limits={k: v for k, v in LIMITS.items() if k != "profile"})
        other = make_record(
            serial="PT-000002",
            started_at=T0 + timedelta(hours=1),
            limits={"name": "old-line", "version": "2", "sha256": "ab" * 32},
        )
        with engine.begin() as connection:
            for record in (shipped, other):
                store_at(connection, "0006", record)
        upgrade(engine)
        with Session(engine) as session:
            stored = session.scalars(select(StoredLimitsProfile.sha256)).all()
            assert stored == [LIMITS["sha256"]]
            latest_only = ReportFilter(since=T0 + timedelta(minutes=30))
            report = eol_report(session, latest_only)
            assert report.bounds_source.startswith("the bounds the roll-ups were counted with")
            assert report.parameters[0].lower == LIMITS["profile"]["offset_counts"]["lower"]
            assert eol_report(session, ReportFilter()).bounds_source.startswith(
                "limits profile kxm52-production v1"
            )
    finally:
        engine.dispose()


def test_the_pose_noise_migration_sums_each_runs_poses(empty_url: str) -> None:
    engine = make_engine(empty_url)
    noise = [RunFacts.noise_sum_x, RunFacts.noise_squares_y, RunFacts.noise_sum_z]
    try:
        upgrade(engine)
        with Session(engine) as session:
            records = [
                make_record(serial=serial, started_at=T0 + timedelta(hours=hour))
                for hour, serial in enumerate(["U1", "U2", "U1"])
            ]
            for record in records:
                RunRepository(session).submit(record)
            session.commit()
            submitted = session.execute(select(*noise).order_by(RunFacts.run_pk)).all()
        expected = [
            (
                sum(p.std.x for p in r.poses),
                sum(p.std.y**2 for p in r.poses),
                sum(p.std.z for p in r.poses),
            )
            for r in records
        ]
        assert [v for row in submitted for v in row] == pytest.approx(
            [v for row in expected for v in row], rel=1e-12
        )
        with engine.begin() as connection:
            command.downgrade(alembic_config(connection), "0010")
        assert "noise_sum_x" not in {c["name"] for c in inspect(engine).get_columns("run_facts")}
        upgrade(engine)
        with Session(engine) as session:
            filled = session.execute(select(*noise).order_by(RunFacts.run_pk)).all()
        assert [v for row in filled for v in row] == pytest.approx(
            [v for row in expected for v in row], rel=1e-12
        )
    finally:
        engine.dispose()
