"""Limits profiles: stored once per SHA-256 from the runs' submissions, read by the report
and the certificate from the database (a profile no limits file on the server holds)."""

from datetime import timedelta

import httpx
from sqlalchemy import select

from db import Database
from db.models import StoredLimitsProfile
from station.domain.product.limits import Bounds, LimitsProfile, load_profile
from station.domain.record.records import document_sha256
from tests.db.records import T0, make_record

RUNS = "/api/v1/runs"
SAFETY_S = 120

#: A profile of this line only: no limits file on the server has its name.
CUSTOM = load_profile().model_copy(
    update={
        "name": "line7-special",
        "version": "4",
        "offset_counts": Bounds(lower=1950, upper=2150),
    }
)


def _submit(client: httpx.Client, key: str, profile: LimitsProfile, hours: int) -> httpx.Response:
    record = make_record(
        serial=f"PT-{hours:06d}", started_at=T0 + timedelta(hours=hours), limits=profile.ref
    )
    return client.post(
        RUNS, json=record.model_dump(mode="json"), headers={"Authorization": f"Bearer {key}"}
    )


def _stored(database: Database) -> dict[str, str]:
    with database.session() as session:
        rows = session.execute(select(StoredLimitsProfile.sha256, StoredLimitsProfile.document))
        return {sha: document for sha, document in rows}


def test_a_profile_is_stored_once_and_a_changed_one_again(
    client: httpx.Client, station_key: str, database: Database
) -> None:
    shipped = load_profile()
    for hours in range(3):
        assert _submit(client, station_key, shipped, hours).status_code == 201
    assert list(_stored(database)) == [shipped.sha256]
    assert _submit(client, station_key, CUSTOM, 3).status_code == 201
    stored = _stored(database)
    assert sorted(stored) == sorted([shipped.sha256, CUSTOM.sha256])
    assert LimitsProfile.model_validate_json(stored[CUSTOM.sha256]) == CUSTOM


def test_a_profile_that_does_not_hash_to_its_sha256_is_422_and_not_stored(
    client: httpx.Client, station_key: str, database: Database
) -> None:
    body = make_record(limits=CUSTOM.ref).model_dump(mode="json")
    body["limits"]["profile"]["offset_counts"]["upper"] = 2500.0
    answer = client.post(RUNS, json=body, headers={"Authorization": f"Bearer {station_key}"})
    assert answer.status_code == 422
    assert "SHA-256" in answer.json()["detail"]
    assert _stored(database) == {}


def test_a_document_not_in_canonical_form_is_422(
    client: httpx.Client, station_key: str, database: Database
) -> None:
    body = make_record().model_dump(mode="json")
    profile = {**body["limits"]["profile"], "retest_limit": None}  # hashes otherwise
    body["limits"] = {**body["limits"], "profile": profile, "sha256": document_sha256(profile)}
    answer = client.post(RUNS, json=body, headers={"Authorization": f"Bearer {station_key}"})
    assert answer.status_code == 422, answer.text
    assert _stored(database) == {}


def test_report_and_certificate_use_the_stored_profile(
    client: httpx.Client, station_key: str
) -> None:
    assert _submit(client, station_key, load_profile(), 0).status_code == 201
    assert _submit(client, station_key, CUSTOM, 1).status_code == 201
    # The first report starts the server's report processes: a generous safety net.
    report = client.get("/api/v1/reports/eol", timeout=SAFETY_S).json()
    offset_x = next(p for p in report["parameters"] if p["name"] == "offset_x")
    assert (offset_x["lower"], offset_x["upper"]) == (1950.0, 2150.0)
    assert "line7-special v4" in report["bounds_source"]
    assert "latest run's" in report["bounds_source"]
    assert offset_x["count"] == 2  # every run in range, against the latest run's bounds
    page = client.get("/api/v1/units/PT-000001/certificate", timeout=SAFETY_S).text
    assert "line7-special v4" in page
    assert "1950" in page
    assert "2150" in page
