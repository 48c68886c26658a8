"""The run repository on SQLite and PostgreSQL: submit, read back, history, lists, keys."""

import hashlib
import json
import uuid
from datetime import timedelta

import pytest
from sqlalchemy import select
from sqlalchemy.orm import Session

from db import RunConflictError, RunQuery, RunRepository
from db.models import RunPose, StationKey
from db.store.repository import KeyHolder, encode_cursor, record_sha256
from station.domain.errors import InputError
from station.domain.record.records import StoredRun
from tests.db.records import LIMITS, T0, make_record


def test_a_submitted_run_reads_back_field_for_field(session: Session) -> None:
    record = make_record(verdict="fail")
    repo = RunRepository(session)
    outcome = repo.submit(record)
    session.commit()
    stored = repo.get(record.run_id)
    assert outcome.created
    assert stored is not None
    assert stored == outcome.run
    assert stored.model_dump(exclude={"received_at"}) == record.model_dump()
    assert stored.received_at.tzinfo is not None


def test_the_poses_a_solve_left_out_read_back(session: Session) -> None:
    plain = make_record(serial="PT-000002")
    assert plain.quality is not None
    record = make_record(quality=plain.quality.model_dump() | {"excluded_poses": (3,)})
    repo = RunRepository(session)
    repo.submit(record)
    repo.submit(plain)
    session.commit()
    stored, stored_plain = repo.get(record.run_id), repo.get(plain.run_id)
    assert stored is not None
    assert stored.quality is not None
    assert stored.quality.excluded_poses == (3,)
    assert stored.model_dump(exclude={"received_at"}) == record.model_dump()
    assert stored_plain is not None
    assert stored_plain.quality is not None
    assert stored_plain.quality.excluded_poses is None


def test_every_pose_is_stored_with_its_replaced_captures(session: Session) -> None:
    record = make_record()
    RunRepository(session).submit(record)
    poses = session.scalars(select(RunPose).order_by(RunPose.index)).all()
    assert [p.name for p in poses] == [p.name for p in record.poses]
    assert poses[0].replaced[0]["reason"] == "moved during capture"
    assert poses[1].crc_errors == 1


def test_a_retry_returns_the_stored_run_without_a_duplicate(session: Session) -> None:
    record = make_record()
    repo = RunRepository(session)
    first = repo.submit(record)
    again = repo.submit(record)
    assert (first.created, again.created) == (True, False)
    assert again.run == first.run
    assert len(repo.history(record.serial)) == 1


def test_the_same_uuid_with_other_content_is_a_conflict(session: Session) -> None:
    record = make_record()
    repo = RunRepository(session)
    repo.submit(record)
    clash = record.model_copy(update={"operator_id": "op-99"})
    with pytest.raises(RunConflictError, match=str(record.run_id)):
        repo.submit(clash)


def test_current_state_is_the_latest_run_and_history_keeps_the_first(session: Session) -> None:
    repo = RunRepository(session)
    retest = make_record(verdict="pass", started_at=T0 + timedelta(hours=2))
    first = make_record(verdict="fail", started_at=T0)
    other_unit = make_record(serial="PT-000002", started_at=T0 + timedelta(hours=5))
    for record in (retest, first, other_unit):  # the late run arrives first
        repo.submit(record)
    latest = repo.latest_for_serial("PT-000001")
    assert latest is not None
    assert (latest.run_id, latest.verdict) == (retest.run_id, "pass")
    history = repo.history("PT-000001")
    assert [r.run_id for r in history] == [first.run_id, retest.run_id]
    assert history[0].failures[0].code == "sensitivity_out_of_range"
    assert repo.latest_for_serial("PT-404") is None


def test_list_filters_and_walks_every_page_once(session: Session) -> None:
    repo = RunRepository(session)
    records = [
        make_record(
            serial=f"PT-{i % 5:06d}",
            station_id=f"line1-st{i % 2}",
            verdict="pass" if i % 3 else "fail",
            started_at=T0 + timedelta(minutes=i // 2),  # pairs share a start time
        )
        for i in range(23)
    ]
    for record in records:
        repo.submit(record)
    seen: list[uuid.UUID] = []
    cursor = None
    while True:
        page = repo.list_runs(RunQuery(station_id="line1-st1", limit=4, cursor=cursor))
        seen += [run.run_id for run in page.runs]
        if page.next_cursor is None:
            break
        cursor = page.next_cursor
    expected = [r for r in records if r.station_id == "line1-st1"]
    assert sorted(seen) == sorted(r.run_id for r in expected)
    assert len(seen) == len(set(seen))

    fails = repo.list_runs(RunQuery(verdict="fail", since=T0 + timedelta(minutes=3))).runs
    assert {r.run_id for r in fails} == {
        r.run_id
        for r in records
        if r.verdict == "fail" and r.started_at >= T0 + timedelta(minutes=3)
    }
    window = repo.list_runs(RunQuery(serial="PT-000001", until=T0 + timedelta(minutes=6))).runs
    assert [r.started_at for r in window] == sorted((r.started_at for r in window), reverse=True)
    assert all(r.serial == "PT-000001" and r.started_at < T0 + timedelta(minutes=6) for r in window)


@pytest.mark.parametrize(
    "cursor",
    [
        "garbage",
        "bm90LWEtY3Vyc29y",
        "",
        encode_cursor(T0, 2**70),  # a run key no database column holds
    ],
)
def test_a_foreign_cursor_is_refused(session: Session, cursor: str) -> None:
    with pytest.raises(InputError, match="cursor"):
        RunRepository(session).list_runs(RunQuery(cursor=cursor))


def test_a_page_size_out_of_range_is_refused(session: Session) -> None:
    with pytest.raises(InputError, match="limit"):
        RunRepository(session).list_runs(RunQuery(limit=0))


def test_keys_are_stored_hashed_and_resolve_to_their_holder_and_scope(session: Session) -> None:
    repo = RunRepository(session)
    key = repo.create_key("line1-st1")
    lab = repo.create_key("line1-st1", "lab")
    session.flush()
    stored = session.scalars(select(StationKey.key_sha256)).all()
    assert not any(key in digest or lab in digest for digest in stored)
    assert repo.key_holder(key) == KeyHolder("line1-st1", "station")
    assert repo.key_holder(lab) == KeyHolder("line1-st1", "lab")
    assert repo.key_holder(key + "x") is None


def test_revoking_a_stations_keys_leaves_a_lab_of_the_same_name_alone(session: Session) -> None:
    repo = RunRepository(session)
    station, lab = repo.create_key("bench-1"), repo.create_key("bench-1", "lab")
    assert repo.revoke_keys("bench-1") == 1
    assert repo.key_holder(station) is None
    assert repo.key_holder(lab) == KeyHolder("bench-1", "lab")
    assert repo.revoke_keys("bench-1", "lab") == 1
    assert repo.key_holder(lab) is None


def test_a_stored_run_survives_a_json_round_trip(session: Session) -> None:
    outcome = RunRepository(session).submit(make_record())
    assert StoredRun.model_validate_json(outcome.run.model_dump_json()) == outcome.run


def test_a_record_without_a_lot_disposition_or_purpose_hashes_as_before_those_existed() -> None:
    reference_only = {key: value for key, value in LIMITS.items() if key != "profile"}
    record = make_record(limits=reference_only)  # an older station's: no profile either
    document = json.loads(record.model_dump_json())
    del document["lot"], document["disposition"], document["purpose"]
    del document["limits"]["profile"], document["quality"]["excluded_poses"]
    del document["gyro_matrix"]  # nor a gyro matrix (whole-unit runs)
    del document["uncertainty"], document["decision_rule"]  # nor these (revision 0013)
    del document["part_number"]  # nor a product (every run was DIXX-A12's)
    del document["as_found"]  # nor what the unit held (revision 0022)
    before = json.dumps(document, separators=(",", ":"), ensure_ascii=False)
    assert record_sha256(record) == hashlib.sha256(before.encode()).hexdigest()
    assert record_sha256(make_record(lot="L1")) != record_sha256(record)
    assert record_sha256(make_record(disposition="ship")) != record_sha256(record)
    assert record_sha256(make_record(purpose="golden")) != record_sha256(record)
    assert record_sha256(make_record(decision_rule="simple")) != record_sha256(record)
    assert record_sha256(make_record(limits=reference_only, part_number="DIXX-D16")) != (
        record_sha256(record)
    )
    assert record_sha256(make_record()) != record_sha256(record)  # with its profile
    held = {"written": False, "offset": [2048.0] * 3, "matrix": [[0.0] * 3] * 3}
    found = {"read_at": "2026-11-02T08:00:00+00:00", "accelerometer": held}
    assert record_sha256(make_record(limits=reference_only, as_found=found)) != (
        record_sha256(record)
    )
