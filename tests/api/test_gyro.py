"""A unit's gyro calibration: the lab fit stored per serial, and the still-pose figures."""

import json
import os
from datetime import UTC, datetime, timedelta
from pathlib import Path

import httpx
import pytest

from db import Database, RunRepository, open_database
from station.domain.gyro import fit_log, paper_truth, read_log, simulate_log
from station.domain.gyro.log import GyroDwells, write_log
from station.domain.record.records import GyroFitRecord
from tests.conftest import CliRunner
from tests.db.records import make_record


@pytest.fixture(scope="module")
def centrifuge_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("gyro") / "centrifuge.csv"
    log, segments = simulate_log(paper_truth(), seed=3)
    with path.open("w") as handle:
        write_log(handle, log, segments)
    return path


def test_the_latest_fit_is_the_units_and_survives_a_round_trip(
    database: Database, centrifuge_log: Path
) -> None:
    report = fit_log(read_log(centrifuge_log))
    old = GyroFitRecord(
        serial="PT000001",
        fitted_at=datetime(2026, 1, 1, tzinfo=UTC),
        source="old.csv",
        report=report,
    )
    new = old.model_copy(
        update={"fitted_at": old.fitted_at + timedelta(days=1), "source": "new.csv"}
    )
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        repository.add_gyro_fit(new)
        repository.add_gyro_fit(old)
    with database.session() as session:
        latest = RunRepository(session).latest_gyro_fit("PT000001")
        assert RunRepository(session).latest_gyro_fit("PT000002") is None
    assert latest is not None
    assert latest.source == "new.csv"
    assert latest.report.g_sensitivity_ppm_per_g == report.g_sensitivity_ppm_per_g


def test_api_serves_the_fit_and_the_latest_runs_gyros(
    client: httpx.Client, database: Database, lab_key: str, centrifuge_log: Path
) -> None:
    record = make_record(serial="PT000009")
    with database.session() as session, session.begin():
        RunRepository(session).submit(record)
    answer = client.get("/api/v1/units/PT000009/gyro")
    assert answer.status_code == 200
    assert answer.json()["fit"] is None
    assert record.gyro is not None
    assert answer.json()["still"]["bias"] == record.gyro.bias.model_dump()
    log = read_log(centrifuge_log)
    report = fit_log(log).to_dict()
    refused = client.post("/api/v1/units/PT000009/gyro", json={"source": "c.csv", "report": report})
    assert refused.status_code == 401
    headers = {"Authorization": f"Bearer {lab_key}"}
    bad = client.post(
        "/api/v1/units/PT000009/gyro",
        json={"source": "c.csv", "report": {"dwells": 1}},
        headers=headers,
    )
    assert bad.status_code == 422
    dwells = GyroDwells.of(log).model_dump()
    stored = client.post(
        "/api/v1/units/PT000009/gyro",
        json={"source": "c.csv", "report": report, "dwells": dwells},
        headers=headers,
    )
    assert stored.status_code == 201, stored.text
    unit = client.get("/api/v1/units/PT000009/gyro").json()
    assert unit["fit"]["source"] == "c.csv"
    assert unit["fit"]["report"]["g_sensitivity_ppm_per_g"] == report["g_sensitivity_ppm_per_g"]
    assert client.get("/api/v1/units/PT000404/gyro").status_code == 404
    assert client.get("/api/v1/units/PT000009").json()["gyro"] == unit["still"]
    certificate = client.get("/api/v1/units/PT000009/certificate")
    assert certificate.status_code == 200
    page = certificate.text
    assert "Gyro error model" in page
    plot = page[page.index('<figure class="chart gyro-plot"') :]
    assert plot.index("<svg") < plot.index("</figure>")
    assert "+581 ppm/g" in plot  # the fitted line's legend, x gyro


@pytest.mark.parametrize(("scope", "holder"), [("station", "line1-st1"), ("quality", "qe-ana")])
def test_only_a_lab_key_stores_a_gyro_fit(
    client: httpx.Client, database: Database, centrifuge_log: Path, scope: str, holder: str
) -> None:
    with database.session() as session, session.begin():
        key = RunRepository(session).create_key(holder, scope)
    log = read_log(centrifuge_log)
    body = {
        "source": "c.csv",
        "report": fit_log(log).to_dict(),
        "dwells": GyroDwells.of(log).model_dump(),
    }
    answer = client.post(
        "/api/v1/units/PT000010/gyro", json=body, headers={"Authorization": f"Bearer {key}"}
    )
    assert answer.status_code == 403
    assert answer.json()["detail"] == (
        f"this API key belongs to {scope} {holder}: gyro fits need a lab key "
        "(calstation keys create --lab ID)"
    )
    assert client.get("/api/v1/units/PT000010/gyro").status_code == 404  # nothing stored


def test_gyro_fit_store_puts_the_fit_where_the_api_reads_it(
    run_cli: CliRunner, centrifuge_log: Path, tmp_path: Path
) -> None:
    env = {**os.environ, "CALSTATION_DATABASE_URL": f"sqlite:///{tmp_path}/r.sqlite3"}
    result = run_cli("gyro", "fit", str(centrifuge_log), "--json", "--store", "PT000123", env=env)
    assert result.returncode == 0, result.stderr
    printed = json.loads(result.stdout)
    database = open_database(env["CALSTATION_DATABASE_URL"])
    with database.session() as session:
        stored = RunRepository(session).latest_gyro_fit("PT000123")
    database.dispose()
    assert stored is not None
    assert stored.source == "centrifuge.csv"
    assert stored.dwells is not None
    assert len(stored.dwells.t) == stored.report.dwells
    assert stored.report.to_dict()["bias_dps"] == printed["bias_dps"]
    bad = run_cli("gyro", "fit", str(centrifuge_log), "--store", "not a serial", env=env)
    assert bad.returncode == 2
    assert "--store: 'not a serial' is not a serial number" in bad.stderr
