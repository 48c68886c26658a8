"""Read endpoints: a unit's state and history, run lists with cursors, single runs, health."""

from datetime import timedelta
from pathlib import Path

import httpx
import pytest
from sqlalchemy import text

from db import Database, RunRepository, open_database
from station.domain.record.records import RunRecord
from tests.db.records import T0, make_record
from tests.servers import local_client, serving


def _store(database: Database, *records: RunRecord) -> None:
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        for record in records:
            repository.submit(record)


def test_health_answers_when_the_database_does(client: httpx.Client) -> None:
    answer = client.get("/healthz")
    assert answer.status_code == 200
    assert answer.json()["status"] == "ok"


def test_a_unit_shows_its_latest_run(client: httpx.Client, database: Database) -> None:
    first = make_record(verdict="fail", started_at=T0)
    retest = make_record(
        offset=(2050.0, 2040.0, 2030.0), started_at=T0 + timedelta(hours=1), lot="L2611-07"
    )
    _store(database, retest, first)
    unit = client.get(f"/api/v1/units/{first.serial}").json()
    assert unit["serial"] == first.serial
    latest, holds = unit["latest"], unit["holds"]
    assert (unit["verdict"], unit["attempts"]) == ("pass", 2)
    assert (latest["run_id"], holds["run_id"]) == (str(retest.run_id), str(retest.run_id))
    assert holds["offset"] == {"x": 2050.0, "y": 2040.0, "z": 2030.0}
    assert holds["sensitivity"] == {"x": 813.95, "y": 815.66, "z": 820.17}
    assert holds["matrix"][0][0] == pytest.approx(1 / 813.95)
    assert holds["written_at"] == latest["finished_at"] == "2026-11-02T09:01:35Z"
    assert latest["station_id"] == holds["station_id"] == retest.station_id
    assert latest["lot"] == "L2611-07"
    assert (latest["failures"], latest["wrote_unit"]) == ([], True)
    history = client.get(f"/api/v1/units/{first.serial}/runs").json()
    assert [r["run_id"] for r in history["data"]] == [str(first.run_id), str(retest.run_id)]
    assert history["data"][0]["failures"][0]["code"] == "sensitivity_out_of_range"


def test_a_unit_holds_the_uncertainty_of_its_coefficients(
    client: httpx.Client, database: Database
) -> None:
    shape = {
        "k": 2.0,
        "offset": {"x": 0.06, "y": 0.07, "z": 0.08},
        "sensitivity": {"x": 0.3, "y": 0.2, "z": 0.25},
        "gyro_bias_dps": [0.004, 0.005, 0.006],
    }
    older = make_record(started_at=T0)  # a record from before: no uncertainty
    record = make_record(started_at=T0 + timedelta(hours=1), uncertainty=shape)
    _store(database, older)
    assert client.get(f"/api/v1/units/{older.serial}").json()["holds"]["uncertainty"] is None
    _store(database, record)
    unit = client.get(f"/api/v1/units/{record.serial}").json()
    assert unit["holds"]["uncertainty"] == shape  # no gyro matrix measured: no key
    run = client.get(f"/api/v1/runs/{record.run_id}").json()
    assert run["uncertainty"] == shape


def test_a_failing_unit_shows_its_failure_reasons(client: httpx.Client, database: Database) -> None:
    record = make_record(verdict="fail")
    _store(database, record)
    unit = client.get(f"/api/v1/units/{record.serial}").json()
    assert unit["verdict"] == "fail"
    assert unit["latest"]["failures"] == [
        {
            "code": "sensitivity_out_of_range",
            "message": "sensitivity z 820.17 counts/g above 819.0",
            "measured": 820.17,
            "lower": pytest.approx(778.24),
            "upper": 819.0,
            "axis": "z",
            "pose": None,
            "uncertainty": None,
        }
    ]


@pytest.mark.parametrize("path", ["/api/v1/units/PT-404", "/api/v1/units/PT-404/runs"])
def test_an_unknown_serial_is_a_404_naming_it(client: httpx.Client, path: str) -> None:
    answer = client.get(path)
    assert answer.status_code == 404
    assert answer.json() == {"detail": "no calibration run of serial PT-404"}


@pytest.mark.parametrize(
    ("path", "status"),
    [
        ("/api/v1/units/bad%20serial", 422),
        ("/api/v1/runs/not-a-uuid", 422),
        ("/api/v1/runs?verdict=maybe", 422),
        ("/api/v1/runs?since=2026-11-02T08:00:00", 422),
        ("/api/v1/runs?limit=0", 422),
        ("/api/v1/runs?limit=100000", 422),
        ("/api/v1/runs?cursor=garbage", 400),
        ("/api/v1/runs?since=0001-01-01T00:00:00%2B14:00", 422),
        ("/api/v1/runs?until=9999-12-31T23:59:59-14:00", 422),
        ("/api/v1/runs/6f1b0c8e-8a52-4f4a-9d43-0c8f6f1e1a11", 404),
        ("/api/v1/nowhere", 404),
    ],
)
def test_bad_reads_are_4xx_with_a_clear_detail(
    client: httpx.Client, path: str, status: int
) -> None:
    answer = client.get(path)
    assert answer.status_code == status
    assert answer.json()["detail"]


def test_run_lists_filter_and_page_with_a_cursor(client: httpx.Client, database: Database) -> None:
    records = [
        make_record(
            serial=f"PT-{i % 3:06d}",
            verdict="fail" if i % 4 == 0 else "pass",
            started_at=T0 + timedelta(minutes=i),
        )
        for i in range(12)
    ]
    _store(database, *records)
    seen: list[str] = []
    params: dict[str, str | int] = {"verdict": "pass", "limit": 2}
    while True:
        page = client.get("/api/v1/runs", params=params).json()
        assert page["count"] == len(page["data"])
        seen += [run["run_id"] for run in page["data"]]
        if page["next_cursor"] is None:
            break
        params["cursor"] = page["next_cursor"]
    passing = sorted(records, key=lambda r: r.started_at, reverse=True)
    assert seen == [str(r.run_id) for r in passing if r.verdict == "pass"]
    window = client.get(
        "/api/v1/runs",
        params={
            "serial": "PT-000001",
            "since": (T0 + timedelta(minutes=2)).isoformat(),
            "until": (T0 + timedelta(minutes=8)).isoformat(),
        },
    ).json()
    assert [run["started_at"] for run in window["data"]] == [
        "2026-11-02T08:07:00Z",
        "2026-11-02T08:04:00Z",
    ]


def test_one_run_comes_with_every_pose(client: httpx.Client, database: Database) -> None:
    record = make_record()
    _store(database, record)
    run = client.get(f"/api/v1/runs/{record.run_id}").json()
    assert len(run["poses"]) == len(record.poses)
    assert run["poses"][0]["replaced"][0]["reason"] == "moved during capture"
    assert RunRecord.model_validate({k: v for k, v in run.items() if k != "received_at"}) == record


def test_reads_can_require_a_station_key(
    keyed_url: str, database: Database, station_key: str
) -> None:
    record = make_record()
    _store(database, record)
    with local_client(keyed_url) as client:
        path = f"/api/v1/units/{record.serial}"
        assert client.get(path).status_code == 401
        assert client.get(path, headers={"Authorization": "Bearer csk_wrong"}).status_code == 401
        answer = client.get(path, headers={"Authorization": f"Bearer {station_key}"})
        assert answer.status_code == 200
        assert client.get("/healthz").status_code == 200


def test_the_openapi_document_lists_every_route(client: httpx.Client) -> None:
    paths = client.get("/openapi.json").json()["paths"]
    assert {
        "/healthz",
        "/api/v1/units/{serial}",
        "/api/v1/units/{serial}/runs",
        "/api/v1/runs",
        "/api/v1/runs/{run_id}",
    } <= set(paths)
    assert client.get("/docs").status_code == 200


def test_a_lookup_the_database_cannot_answer_is_a_503_and_the_server_recovers(
    tmp_path: Path,
) -> None:
    url = f"sqlite:///{tmp_path / 'results.sqlite3'}"
    database = open_database(url, auto_migrate=True)
    record = make_record()
    _store(database, record)
    path = f"/api/v1/units/{record.serial}"
    with serving(url) as base, local_client(base, timeout=10) as client:
        assert client.get(path).status_code == 200
        with database.engine.begin() as connection:  # the table goes away under the server
            connection.execute(text("ALTER TABLE units RENAME TO units_away"))
        broken = client.get(path)
        with database.engine.begin() as connection:
            connection.execute(text("ALTER TABLE units_away RENAME TO units"))
        again = client.get(path)
    database.dispose()
    assert broken.status_code == 503
    assert broken.json() == {"detail": "results database unavailable"}
    assert again.status_code == 200
    assert again.json()["latest"]["run_id"] == str(record.run_id)
