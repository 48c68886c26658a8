"""``POST /api/v1/runs``: keys, idempotency, the server's own solve, and refused bodies."""

import json
import uuid

import httpx
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from db import Database, RunRepository
from tests.conftest import examples
from tests.db.records import make_record

RUNS = "/api/v1/runs"


def _auth(key: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {key}"}


def test_a_submitted_run_is_stored_and_a_retry_returns_it(
    client: httpx.Client, station_key: str
) -> None:
    record = make_record()
    body = record.model_dump(mode="json")
    first = client.post(RUNS, json=body, headers=_auth(station_key))
    retry = client.post(RUNS, json=body, headers=_auth(station_key))
    assert first.status_code == 201, first.text
    assert first.headers["Location"] == f"{RUNS}/{record.run_id}"
    assert retry.status_code == 200
    assert retry.json() == first.json()
    stored = client.get(f"{RUNS}/{record.run_id}").json()
    assert stored == first.json()
    assert len(client.get(f"/api/v1/units/{record.serial}/runs").json()["data"]) == 1


def test_the_same_uuid_with_other_content_is_a_conflict(
    client: httpx.Client, station_key: str
) -> None:
    record = make_record()
    client.post(RUNS, json=record.model_dump(mode="json"), headers=_auth(station_key))
    clash = record.model_copy(update={"operator_id": "op-2"}).model_dump(mode="json")
    answer = client.post(RUNS, json=clash, headers=_auth(station_key))
    assert answer.status_code == 409
    assert str(record.run_id) in answer.json()["detail"]


def test_a_failed_run_without_coefficients_is_stored(
    client: httpx.Client, station_key: str
) -> None:
    record = make_record(verdict="fail", coefficients=None, quality=None)
    answer = client.post(RUNS, json=record.model_dump(mode="json"), headers=_auth(station_key))
    assert answer.status_code == 201, answer.text
    unit = client.get(f"/api/v1/units/{record.serial}").json()
    assert (unit["verdict"], unit["holds"], unit["latest"]["wrote_unit"]) == ("fail", None, False)


@pytest.mark.parametrize(
    ("headers", "status", "message"),
    [
        ({}, 401, "API key is required"),
        ({"Authorization": "Bearer csk_not-a-key"}, 401, "unknown or revoked"),
        ({"Authorization": "Basic dXNlcjpwYXNz"}, 401, "API key is required"),
    ],
)
def test_submitting_needs_a_valid_station_key(
    client: httpx.Client, headers: dict[str, str], status: int, message: str
) -> None:
    answer = client.post(RUNS, json=make_record().model_dump(mode="json"), headers=headers)
    assert answer.status_code == status
    assert message in answer.json()["detail"]


def test_a_station_submits_only_its_own_runs(client: httpx.Client, database: Database) -> None:
    with database.session() as session, session.begin():
        other_key = RunRepository(session).create_key("line2-st9")
    answer = client.post(RUNS, json=make_record().model_dump(mode="json"), headers=_auth(other_key))
    assert answer.status_code == 403
    assert answer.json()["detail"] == (
        "this API key belongs to station line2-st9, the run to line1-st1"
    )


@pytest.mark.parametrize(("scope", "holder"), [("lab", "gyro-lab"), ("quality", "qe-ana")])
def test_a_lab_or_quality_key_stores_no_runs_and_is_told_its_own_scope(
    client: httpx.Client, database: Database, scope: str, holder: str
) -> None:
    with database.session() as session, session.begin():
        key = RunRepository(session).create_key(holder, scope)
    record = make_record()
    answer = client.post(RUNS, json=record.model_dump(mode="json"), headers=_auth(key))
    assert answer.status_code == 403
    assert answer.json()["detail"] == (
        f"this API key belongs to {scope} {holder}: runs need their station's key "
        "(calstation keys create --station ID)"
    )
    assert client.get(f"{RUNS}/{record.run_id}").status_code == 404


@pytest.mark.parametrize(
    ("field", "change", "where"),
    [
        ("offset", {"x": 2081.9 + 0.5, "y": 2041.2, "z": 1960.5}, "offset[0]"),
        ("sensitivity", {"x": 813.95, "y": 815.66, "z": 820.17 * 1.001}, "sensitivity[2]"),
    ],
)
def test_coefficients_the_poses_do_not_give_are_refused(
    client: httpx.Client, station_key: str, field: str, change: dict[str, float], where: str
) -> None:
    body = make_record().model_dump(mode="json")
    body["coefficients"][field] = change
    answer = client.post(RUNS, json=body, headers=_auth(station_key))
    assert answer.status_code == 422
    [error] = answer.json()["errors"]
    assert error["loc"] == "body.coefficients"
    assert error["msg"].startswith(where)


def test_coefficients_from_degenerate_poses_are_refused(
    client: httpx.Client, station_key: str
) -> None:
    body = make_record().model_dump(mode="json")
    for pose in body["poses"]:
        pose["mean"] = {"x": 2048.0, "y": 2048.0, "z": 2867.2}
    answer = client.post(RUNS, json=body, headers=_auth(station_key))
    assert answer.status_code == 422
    assert "give no calibration" in answer.json()["detail"]


@pytest.mark.parametrize(
    ("body", "message"),
    [
        (b'{"run_id": ', "JSON decode error"),
        (b"[]", "body"),
        (json.dumps({"serial": "PT-1"}).encode(), "run_id: Field required"),
        (b"", "body: Field required"),
    ],
)
def test_malformed_bodies_get_422_naming_the_problem(
    client: httpx.Client, station_key: str, body: bytes, message: str
) -> None:
    answer = client.post(
        RUNS,
        content=body,
        headers={**_auth(station_key), "Content-Type": "application/json"},
    )
    assert answer.status_code == 422
    assert message in answer.json()["detail"]


def test_oversized_bodies_are_refused_with_413(client: httpx.Client, station_key: str) -> None:
    huge = b'{"pad": "' + b"x" * 2_000_000 + b'"}'
    declared = client.post(RUNS, content=huge, headers=_auth(station_key))
    streamed = client.post(
        RUNS, content=iter([huge[:600_000], huge[600_000:]]), headers=_auth(station_key)
    )
    for answer in (declared, streamed):
        assert answer.status_code == 413
        assert "larger than" in answer.json()["detail"]


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=20),
    lambda children: (
        st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=10), children, max_size=4)
    ),
    max_leaves=20,
)


@settings(
    max_examples=examples(60),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(
    field=st.sampled_from(list(make_record().model_dump(mode="json"))),
    value=json_values,
)
def test_no_body_ever_gets_a_5xx(
    client: httpx.Client, station_key: str, field: str, value: object
) -> None:
    body = make_record(run_id=uuid.uuid4()).model_dump(mode="json")
    body[field] = value
    answer = client.post(
        RUNS,
        content=json.dumps(body, allow_nan=True),
        headers={**_auth(station_key), "Content-Type": "application/json"},
    )
    assert answer.status_code < 500, answer.text
    assert answer.is_success or answer.json()["detail"]


#: RunPose means: mostly ADC counts, sometimes any float at all.
any_count = st.one_of(
    st.floats(min_value=0.0, max_value=4095.0),
    st.floats(allow_nan=False, allow_infinity=False),
)


@settings(
    max_examples=examples(40),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(means=st.lists(st.tuples(any_count, any_count, any_count), min_size=7, max_size=7))
def test_any_pose_means_get_an_answer_never_a_5xx(
    client: httpx.Client, station_key: str, means: list[tuple[float, float, float]]
) -> None:
    body = make_record(run_id=uuid.uuid4()).model_dump(mode="json")
    for pose, mean in zip(body["poses"], means, strict=True):
        pose["mean"] = dict(zip("xyz", mean, strict=True))
    answer = client.post(RUNS, json=body, headers=_auth(station_key))
    assert answer.status_code in (201, 422), answer.text


def test_poses_left_out_must_be_the_ones_the_poses_give(
    client: httpx.Client, station_key: str
) -> None:
    # Six fit poses leave nothing to leave out: a record claiming pose 3 was is refused.
    body = make_record().model_dump(mode="json")
    body["quality"]["excluded_poses"] = [2]
    answer = client.post(RUNS, json=body, headers=_auth(station_key))
    assert answer.status_code == 422
    assert "quality.excluded_poses: submitted [2], the poses give [none]" in answer.text
