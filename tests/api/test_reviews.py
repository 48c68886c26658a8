"""Quality reviews of units on hold, through the real server: who may store one, of
which run, and that the record is append-only and read back as stored."""

from datetime import timedelta

import httpx

from db import Database, RunRepository
from tests.db.records import T0, make_record

REVIEW = {
    "root_cause": "accel y stuck: cracked solder joint on U3",
    "repair_action": "U3 reflowed, y axis checked on the bench",
    "decision": "retest",
}


def _store(database: Database, *verdicts: str) -> list[str]:
    records = [
        make_record(serial="PT000310", verdict=v, started_at=T0 + timedelta(hours=i))
        for i, v in enumerate(verdicts)
    ]
    with database.session() as session, session.begin():
        for record in records:
            RunRepository(session).submit(record)
    return [str(r.run_id) for r in records]


def test_a_quality_key_reviews_the_units_latest_failed_run_and_it_reads_back(
    client: httpx.Client, database: Database, quality_key: str
) -> None:
    _, held = _store(database, "fail", "fail")
    body = {"run_id": held, **REVIEW}
    answer = client.post(
        "/api/v1/units/PT000310/reviews",
        json=body,
        headers={"Authorization": f"Bearer {quality_key}"},
    )
    assert answer.status_code == 201, answer.text
    stored = answer.json()
    assert stored["reviewer"] == "qe-ana"
    assert stored["decision"] == "retest"
    assert stored["run_id"] == held
    listed = client.get("/api/v1/units/PT000310/reviews").json()
    assert listed == {"data": [stored], "count": 1}
    assert client.get("/api/v1/units/PT000999/reviews").json() == {"data": [], "count": 0}


def test_only_a_quality_key_reviews_and_only_the_latest_failed_run(
    client: httpx.Client, database: Database, quality_key: str, station_key: str
) -> None:
    first, latest = _store(database, "fail", "pass")
    path = "/api/v1/units/PT000310/reviews"

    def post(key: str | None, run_id: str, **change: str) -> httpx.Response:
        headers = {"Authorization": f"Bearer {key}"} if key else {}
        return client.post(path, json={"run_id": run_id, **REVIEW, **change}, headers=headers)

    assert post(None, latest).status_code == 401
    refused = post(station_key, latest)
    assert refused.status_code == 403
    assert "need a quality key" in refused.json()["detail"]
    stale = post(quality_key, first)
    assert stale.status_code == 409
    assert f"is not the latest run of PT000310 (run {latest} is)" in stale.json()["detail"]
    passed = post(quality_key, latest)
    assert passed.status_code == 409
    assert "is not on hold: its latest run" in passed.json()["detail"]
    assert post(quality_key, latest, decision="keep").status_code == 422
    assert post(quality_key, latest, root_cause="  ").status_code == 422
    assert post(quality_key, latest, root_cause="line\x00break").status_code == 422
    unknown = client.post(
        "/api/v1/units/PT000999/reviews",
        json={"run_id": latest, **REVIEW},
        headers={"Authorization": f"Bearer {quality_key}"},
    )
    assert unknown.status_code == 409
    assert client.get(f"{path}").json()["count"] == 0
