"""The report, certificate and dashboard routes on a live server, on both backends."""

import csv
import io
import re
from datetime import timedelta

import httpx
import pytest

from db import Database, RunRepository
from tests.db.eol_data import insert_line_history
from tests.db.records import T0, make_record

RANGE = {"from": "2026-11-02T08:00:00Z", "to": "2026-11-02T10:00:00Z"}


@pytest.fixture
def line(database: Database) -> None:
    """The hand-built line history of :mod:`tests.db.eol_data`."""
    with database.session() as session:
        insert_line_history(session)


@pytest.mark.usefixtures("line")
def test_json_report_holds_the_hand_computed_yields(client: httpx.Client) -> None:
    answer = client.get("/api/v1/reports/eol", params=RANGE)
    assert answer.status_code == 200
    assert answer.headers["content-type"] == "application/json"
    report = answer.json()
    summary = report["summary"]
    assert (summary["runs"], summary["units_tested"], summary["units_passed"]) == (7, 5, 3)
    assert summary["first_pass_yield"] == pytest.approx(2 / 5)
    assert [(e["code"], e["count"]) for e in report["pareto"]] == [
        ("offset", 2),
        ("sensitivity", 1),
        ("verification_error", 1),
    ]
    assert report["filter"]["since"].startswith("2026-11-02T08:00:00")


@pytest.mark.usefixtures("line")
def test_csv_and_html_show_the_numbers_of_the_json(client: httpx.Client) -> None:
    report = client.get("/api/v1/reports/eol", params=RANGE).json()
    answer = client.get("/api/v1/reports/eol", params={**RANGE, "format": "csv"})
    assert answer.headers["content-type"].startswith("text/csv")
    cells = {
        (row["section"], row["item"], row["metric"]): row["value"]
        for row in csv.DictReader(io.StringIO(answer.text))
    }
    for key, value in report["summary"].items():
        assert cells["summary", "", key] == str(value)
    for stats in report["parameters"]:
        for key in ("count", "mean", "std", "cp", "cpk", "marginal"):
            assert cells["parameter", stats["name"], key] == (
                "" if stats[key] is None else str(stats[key])
            )
    for unit in report["units"]:
        assert cells["unit", unit["serial"], "disposition"] == unit["disposition"]
    html = client.get("/api/v1/reports/eol", params={**RANGE, "format": "html"}).text
    s = report["summary"]
    for fraction in (s["report_yield"], s["first_pass_yield"], s["final_yield"]):
        assert f"{100 * fraction:.1f} %" in html
    assert html.count("<svg") == 1 + len(report["parameters"]) + len(report["control_charts"])
    assert "http://" not in html.replace('xmlns="http://www.w3.org/2000/svg"', "")


@pytest.mark.usefixtures("line")
def test_station_filter_and_a_bad_bound(client: httpx.Client) -> None:
    st2 = client.get("/api/v1/reports/eol", params={**RANGE, "station": "st2"}).json()
    assert (st2["summary"]["runs"], st2["summary"]["units_tested"]) == (3, 2)
    bad = client.get("/api/v1/reports/eol", params={"from": "last tuesday"})
    assert bad.status_code == 422
    [error] = bad.json()["errors"]
    assert error["loc"] == "query.from"
    assert "from 'last tuesday' is not an ISO date" in error["msg"]
    assert client.get("/api/v1/reports/eol", params={"format": "pdf"}).status_code == 422


@pytest.mark.usefixtures("line")
def test_certificate_of_a_unit_and_of_an_unknown_one(client: httpx.Client) -> None:
    answer = client.get("/api/v1/units/U3/certificate")
    assert answer.status_code == 200
    assert answer.headers["content-type"].startswith("text/html")
    page = answer.text
    assert "U3" in page
    assert re.search(r'class="fail">fail<', page)
    assert "verification_error out of limits" in page
    assert page.count("<tr><td>") >= 7  # one row per pose at least
    missing = client.get("/api/v1/units/NOPE-1/certificate")
    assert missing.status_code == 404
    assert missing.json()["detail"] == "no calibration run of serial NOPE-1"


def test_dashboard_follows_the_event_stream_and_draws_its_charts(client: httpx.Client) -> None:
    answer = client.get("/")
    assert answer.status_code == 200
    page = answer.text
    assert 'http-equiv="refresh"' not in page  # no full reload
    assert 'new EventSource("/api/v1/events")' in page
    assert "Line dashboard" in page
    assert "<svg" in page  # the Pareto, even with no run today


def test_lot_filters_the_report_and_the_run_list_and_shows_on_the_pages(
    client: httpx.Client, database: Database
) -> None:
    with database.session() as session:
        repository = RunRepository(session)
        for i, lot in enumerate(["L-7", "L-8", None]):
            repository.submit(
                make_record(serial=f"U{i}", lot=lot, started_at=T0 + timedelta(minutes=i))
            )
        session.commit()
    report = client.get("/api/v1/reports/eol", params={**RANGE, "lot": "L-7"}).json()
    assert (report["summary"]["runs"], report["filter"]["lot"]) == (1, "L-7")
    assert [u["serial"] for u in report["units"]] == ["U0"]
    runs = client.get("/api/v1/runs", params={"lot": "L-8"}).json()
    assert [(r["serial"], r["lot"]) for r in runs["data"]] == [("U1", "L-8")]
    html = client.get("/api/v1/reports/eol", params={**RANGE, "lot": "L-7", "format": "html"})
    assert "· lot L-7" in html.text
    assert "<tr><th>lot</th><td>L-8</td></tr>" in client.get("/api/v1/units/U1/certificate").text
