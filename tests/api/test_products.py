"""Products over the API: every run names its part number; the run list, the unit's
answer and the end-of-line report carry it and filter by it."""

import csv
import html
import io
import json
import os
import re
from datetime import timedelta
from pathlib import Path

import httpx
import pytest
from sqlalchemy import text

from db import Database, RunRepository
from station.domain.product.limits import load_profile
from tests.conftest import CliRunner
from tests.db.records import T0, make_record
from tests.servers import STATION

RANGE = {"from": "2026-11-01T00:00Z", "to": "2026-11-04T00:00Z"}
#: A product the server does not ship (a plant's own products file): a 14-bit sensor.
OWN_PRODUCT = "PLANT-X14"
#: A DIXX-D16 unit's offset and sensitivity: 16-bit counts around 32 768, 8 192 counts/g.
D16_OFFSET = (33010.5, 32540.25, 31980.0)
D16_SENSITIVITY = (8150.0, 8240.5, 8190.0)


def _store(database: Database) -> None:
    with database.session() as session:
        repository = RunRepository(session)
        for i, (part, verdict) in enumerate(
            [("DIXX-A12", "pass"), ("DIXX-D16", "pass"), ("DIXX-D16", "fail")]
        ):
            extra = {"coefficients": None, "quality": None} if verdict == "fail" else {}
            repository.submit(
                make_record(
                    serial=f"PT-00010{i}",
                    part_number=part,
                    verdict=verdict,
                    started_at=T0 + timedelta(minutes=i),
                    **extra,
                )
            )
        # A record that names no product (an older station's) is the first product's.
        older = make_record(serial="PT-000109", started_at=T0 + timedelta(minutes=9))
        document = older.model_dump(mode="json")
        del document["part_number"]
        repository.submit(type(older).model_validate(document))
        session.commit()


def test_the_run_list_and_the_unit_carry_and_filter_the_part_number(
    client: httpx.Client, database: Database
) -> None:
    _store(database)
    runs = client.get("/api/v1/runs", params={"part_number": "DIXX-D16"}).json()["data"]
    assert sorted((r["serial"], r["part_number"]) for r in runs) == [
        ("PT-000101", "DIXX-D16"),
        ("PT-000102", "DIXX-D16"),
    ]
    every = client.get("/api/v1/runs").json()["data"]
    assert {r["serial"]: r["part_number"] for r in every}["PT-000109"] == "DIXX-A12"
    unit = client.get("/api/v1/units/PT-000101").json()
    assert unit["latest"]["part_number"] == "DIXX-D16"
    assert client.get("/api/v1/runs/" + runs[0]["run_id"]).json()["part_number"] == "DIXX-D16"
    refused = client.get("/api/v1/runs", params={"part_number": "no such part"})
    assert refused.status_code == 422


def test_the_eol_report_of_one_product(client: httpx.Client, database: Database) -> None:
    _store(database)
    d16 = client.get("/api/v1/reports/eol", params={**RANGE, "part_number": "DIXX-D16"}).json()
    assert d16["filter"]["part_number"] == "DIXX-D16"
    assert (d16["summary"]["runs"], d16["summary"]["runs_passed"]) == (2, 1)
    a12 = client.get("/api/v1/reports/eol", params={**RANGE, "part_number": "DIXX-A12"}).json()
    assert (a12["summary"]["runs"], a12["summary"]["runs_passed"]) == (2, 2)
    line = client.get("/api/v1/reports/eol", params=RANGE).json()
    assert line["summary"]["runs"] == 4
    # Without a range too: the product's runs are read from the runs themselves.
    open_range = client.get("/api/v1/reports/eol", params={"part_number": "DIXX-D16"}).json()
    assert open_range["summary"]["runs"] == 2


def _raw_product_counts(database: Database) -> dict[str, tuple[int, int, int, int, int]]:
    """Per part number, from the stored runs by raw SQL: (runs, runs passed, units,
    units whose first run passed, units whose latest run passed); no aborts stored."""
    with database.session() as session:
        stored = session.execute(
            text("SELECT part_number, serial, verdict FROM runs ORDER BY started_at, id")
        ).all()
    counts = {}
    for part in sorted({row.part_number for row in stored}):
        runs = [(row.serial, row.verdict) for row in stored if row.part_number == part]
        first = {serial: verdict for serial, verdict in reversed(runs)}
        latest = dict(runs)
        counts[part] = (
            len(runs),
            sum(verdict == "pass" for _, verdict in runs),
            len(first),
            sum(verdict == "pass" for verdict in first.values()),
            sum(verdict == "pass" for verdict in latest.values()),
        )
    return counts


def test_the_eol_report_has_a_row_per_product_in_json_csv_and_html(
    client: httpx.Client, database: Database
) -> None:
    _store(database)
    with database.session() as session:  # a retest of a D16 unit, now passing
        RunRepository(session).submit(
            make_record(
                serial="PT-000102", part_number="DIXX-D16", started_at=T0 + timedelta(minutes=20)
            )
        )
        session.commit()
    expected = _raw_product_counts(database)
    report = client.get("/api/v1/reports/eol", params=RANGE).json()
    rows = {p["part_number"]: p["summary"] for p in report["products"]}
    assert list(rows) == sorted(expected)
    for part, summary in rows.items():
        fields = ("runs", "runs_passed", "units_tested", "first_pass_units", "units_passed")
        assert tuple(summary[f] for f in fields) == expected[part]
    for field in ("runs", "runs_passed", "units_tested", "units_passed"):
        assert sum(s[field] for s in rows.values()) == report["summary"][field]

    answer = client.get("/api/v1/reports/eol", params={**RANGE, "format": "csv"})
    cells = {
        (row["section"], row["item"], row["metric"]): row["value"]
        for row in csv.DictReader(io.StringIO(answer.text))
    }
    for part, summary in rows.items():
        for key, value in summary.items():
            assert cells["product", part, key] == ("" if value is None else str(value))

    page = client.get("/api/v1/reports/eol", params={**RANGE, "format": "html"}).text
    table = re.search(r'<table class="summary products">(.*?)</table>', page, re.S)
    assert table is not None
    shown = [
        [html.unescape(cell) for cell in re.findall(r"<td>(.*?)</td>", row)]
        for row in re.findall(r"<tr>(.*?)</tr>", table.group(1), re.S)[1:]
    ]
    assert [row[0] for row in shown] == sorted(expected)
    for row in shown:
        summary = rows[row[0]]
        assert row[1:5] == [
            str(summary[f]) for f in ("units_tested", "units_passed", "units_failed", "runs")
        ]
        for fraction, cell in zip(
            (summary["report_yield"], summary["first_pass_yield"], summary["final_yield"]),
            row[5:8],
            strict=True,
        ):
            assert cell == f"{100 * fraction:.1f} %"


def test_a_submitted_run_keeps_its_product_and_a_retry_is_the_same_run(
    client: httpx.Client, station_key: str
) -> None:
    record = make_record(
        serial="PT-000201", part_number="DIXX-D16", offset=D16_OFFSET, sensitivity=D16_SENSITIVITY
    )
    headers = {"Authorization": f"Bearer {station_key}"}
    body = record.model_dump(mode="json")
    assert client.post("/api/v1/runs", json=body, headers=headers).status_code == 201
    assert client.post("/api/v1/runs", json=body, headers=headers).status_code == 200
    other = {**body, "part_number": OWN_PRODUCT}
    assert client.post("/api/v1/runs", json=other, headers=headers).status_code == 409


@pytest.mark.parametrize(
    ("part_number", "offset", "sensitivity"),
    [
        ("DIXX-D16", D16_OFFSET, D16_SENSITIVITY),
        (OWN_PRODUCT, (8250.0, 8120.0, 8190.0), (2040.0, 2052.0, 2049.5)),
    ],
    ids=["d16", "own-product"],
)
def test_the_server_verifies_a_run_in_its_own_products_counts(
    client: httpx.Client,
    station_key: str,
    part_number: str,
    offset: tuple[float, float, float],
    sensitivity: tuple[float, float, float],
) -> None:
    """A DIXX-D16 run reads tens of thousands of counts, far beyond the putter's 12-bit
    rails: the server re-solves it in its own sensor's counts and stores it; tampered
    coefficients of the same run are still refused."""
    headers = {"Authorization": f"Bearer {station_key}"}
    limits = load_profile(name="dixx-d16-production").ref.model_dump(mode="json")
    record = make_record(
        part_number=part_number, offset=offset, sensitivity=sensitivity, limits=limits
    )
    body = record.model_dump(mode="json")
    answer = client.post("/api/v1/runs", json=body, headers=headers)
    assert answer.status_code == 201, answer.text
    assert answer.json()["part_number"] == part_number
    tampered = make_record(
        part_number=part_number, offset=offset, sensitivity=sensitivity, limits=limits
    ).model_dump(mode="json")
    tampered["coefficients"]["offset"]["y"] += 1.0
    refused = client.post("/api/v1/runs", json=tampered, headers=headers)
    assert refused.status_code == 422, refused.text
    assert refused.json()["errors"][0]["msg"].startswith("offset[1]")


@pytest.mark.timeout(120)
def test_a_d16_station_stores_its_runs_through_the_server(
    run_cli: CliRunner, tmp_path: Path, live_url: str, station_key: str, client: httpx.Client
) -> None:
    """``demo --config`` of a station storing through the server,
    two DIXX-D16 putters: both runs stored, none set aside as refused."""
    config = tmp_path / "station.toml"
    config.write_text(f'server_url = "{live_url}"\napi_key = "{station_key}"\n')
    env = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    env["CALSTATION_DATA_DIR"] = str(tmp_path / "data")
    result = run_cli(
        "demo", "--config", str(config), "--station", STATION, "--part-number", "DIXX-D16",
        "--units", "2", "--speed", "20", "--json", env=env, timeout=110,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert [u["verdict"] for u in json.loads(result.stdout)] == ["pass", "pass"]
    refused = tmp_path / "data" / "outbox" / "refused"
    assert not refused.exists() or not any(refused.iterdir())
    runs = client.get("/api/v1/runs", params={"part_number": "DIXX-D16"}).json()["data"]
    assert len(runs) == 2
