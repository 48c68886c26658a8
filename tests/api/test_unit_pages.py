"""A unit's page, its certificate or failure report, and the line's event stream, on a live
server on both backends."""

import html
import json
import re
from collections.abc import Iterator
from datetime import timedelta

import httpx
import pytest

from db import Database, RunRepository
from station.domain.record.records import RunRecord
from tests.db.records import LIMITS, T0, make_record
from tests.servers import STATION

#: A failure with its value and limits, as the station records an offset out of limits.
OFFSET_X_HIGH = {
    "code": "offset",
    "message": "offset x out of limits",
    "measured": 2301.5,
    "lower": 1848.0,
    "upper": 2248.0,
    "axis": "x",
}


def _store(database: Database, *records: RunRecord) -> None:
    with database.session() as session:
        repository = RunRepository(session)
        for record in records:
            repository.submit(record)
        session.commit()


@pytest.fixture
def retested(database: Database) -> list[str]:
    """U1 failed, then passed at another station; U2 failed twice. Returns the run ids."""
    runs = [
        make_record(serial="U1", verdict="fail", failures=[OFFSET_X_HIGH], started_at=T0),
        make_record(
            serial="U1",
            station_id="line1-st2",
            operator_id="op-b",
            started_at=T0 + timedelta(minutes=5),
        ),
        make_record(serial="U2", verdict="fail", failures=[OFFSET_X_HIGH], started_at=T0),
        make_record(
            serial="U2",
            verdict="fail",
            failures=[OFFSET_X_HIGH],
            started_at=T0 + timedelta(minutes=9),
        ),
    ]
    _store(database, *runs)
    return [str(run.run_id) for run in runs]


def test_a_unit_page_lists_every_run_and_links_each_record(
    client: httpx.Client, retested: list[str]
) -> None:
    answer = client.get("/units/U1")
    assert answer.status_code == 200
    assert answer.headers["content-type"].startswith("text/html")
    page = answer.text
    assert page.count('<tr class="run">') == 2
    for run_id in retested[:2]:
        assert f'href="/api/v1/runs/{run_id}"' in page
    assert retested[2] not in page  # U2's runs are not U1's
    assert "line1-st2" in page
    assert "op-b" in page
    # what failed in the station's words, its value and limits
    assert "offset x out of limits (measured 2301.5, limits 1848 … 2248)" in page
    assert '<b id="verdict" class="pass">pass</b>' in page
    assert 'href="/api/v1/units/U1/certificate">Calibration certificate</a>' in page
    # the JSON answer at the API's path is unchanged
    assert client.get("/api/v1/units/U1").json()["attempts"] == 2


def test_a_failed_unit_gets_a_failure_report_not_a_certificate(
    client: httpx.Client, retested: list[str]
) -> None:
    unit = client.get("/units/U2").text
    assert 'href="/api/v1/units/U2/certificate">Failure report</a>' in unit
    assert "Calibration certificate" not in unit
    report = client.get("/api/v1/units/U2/certificate").text
    assert "<h1>Failure report</h1>" in report
    assert "Calibration certificate" not in report
    assert re.search(
        r"<td>offset</td><td>offset x out of limits</td><td>2301.5</td>"
        r"<td>1848</td><td>2248</td>",
        report,
    )
    # the earlier run is listed on it, with a link to its record
    earlier = report.split("<h2>Earlier runs</h2>")[1]
    assert earlier.count(f'href="/api/v1/runs/{retested[2]}"') == 1
    assert retested[3] not in earlier


def test_a_certificate_lists_the_earlier_runs(client: httpx.Client, retested: list[str]) -> None:
    page = client.get("/api/v1/units/U1/certificate").text
    assert "<h1>Calibration certificate</h1>" in page
    earlier = page.split("<h2>Earlier runs</h2>")[1]
    assert f'href="/api/v1/runs/{retested[0]}"' in earlier
    assert 'class="fail">fail<' in earlier


def test_a_certificate_prints_each_coefficient_with_its_uncertainty_and_k(
    client: httpx.Client, database: Database
) -> None:
    shape = {
        "k": 2.0,
        "offset": {"x": 0.0612, "y": 0.0713, "z": 0.0814},
        "sensitivity": {"x": 0.312, "y": 0.213, "z": 0.254},
        "gyro_bias_dps": [0.00412, 0.00513, 0.00614],
    }
    _store(database, make_record(serial="U9", uncertainty=shape), make_record(serial="U8"))
    page = client.get("/api/v1/units/U9/certificate").text
    coefficients = page.split("<h2>Coefficients</h2>")[1].split("<h2>Limits</h2>")[0]
    for value in ("0.0612", "0.0713", "0.0814", "0.312", "0.213", "0.254"):
        assert f" ± {value}</td>" in coefficients
    assert "coverage factor k = 2 " in coefficients
    gyro = page.split("<h2>Gyro</h2>")[1]
    assert " ± 0.00412</td>" in gyro
    older = client.get("/api/v1/units/U8/certificate").text
    assert " ± " not in older.split("<h2>Coefficients</h2>")[1].split("<h2>Limits</h2>")[0]
    assert "No uncertainty recorded for this run." in older


def test_an_unknown_serial_is_a_404_page_and_a_malformed_one_a_422(
    client: httpx.Client,
) -> None:
    missing = client.get("/units/NOPE-1")
    assert missing.status_code == 404
    assert missing.headers["content-type"].startswith("text/html")
    assert "No calibration run of serial NOPE-1 is stored." in missing.text
    for bad in ("-leading-dash", "a%20b", "x" * 65, "a%00b"):
        answer = client.get(f"/units/{bad}")
        assert answer.status_code == 422, bad
        assert answer.json()["errors"][0]["loc"] == "path.serial"


@pytest.fixture
def events(client: httpx.Client) -> Iterator[Iterator[str]]:
    """The lines of the event stream, opened (its headers received) before the test goes on."""
    with client.stream("GET", "/api/v1/events", timeout=httpx.Timeout(60)) as answer:
        assert answer.status_code == 200
        assert answer.headers["content-type"].startswith("text/event-stream")
        yield answer.iter_lines()


@pytest.mark.timeout(90)
def test_a_run_submitted_through_the_api_is_pushed_to_the_event_stream(
    client: httpx.Client, events: Iterator[str], station_key: str
) -> None:
    record = make_record(serial="PT-EVENT-1", verdict="fail", failures=[OFFSET_X_HIGH])
    stored = client.post(
        "/api/v1/runs",
        json=record.model_dump(mode="json"),
        headers={"Authorization": f"Bearer {station_key}"},
    )
    assert stored.status_code == 201
    data = next(line for line in events if line.startswith("data: "))
    event = json.loads(data.removeprefix("data: "))
    assert event["run_id"] == str(record.run_id)
    assert (event["serial"], event["station_id"], event["verdict"]) == (
        "PT-EVENT-1",
        STATION,
        "fail",
    )
    assert (event["failure"], event["unit"]) == ("offset", "/units/PT-EVENT-1")


def test_the_dashboard_lists_the_units_on_hold_with_what_they_hold(
    client: httpx.Client, retested: list[str]
) -> None:
    page = client.get("/").text
    assert "Units on hold (latest 1 of 1, any day)" in page
    held = page.split('<table class="held">')[1].split("</table>")[0]
    assert '<a class="serial" href="/units/U2">U2</a>' in held
    assert "U1" not in held  # passed at its retest
    assert "no verified coefficients" not in held  # its failed runs wrote it (offset limits)
    assert "coefficients of a failed run" in held


def _identity(page: str) -> str:
    """The identity block and method of a certificate or failure report (its text
    unescaped: a translated line's apostrophe is escaped as any text is)."""
    return html.unescape(page.split('<table class="identity">')[1].split("<h2>Limits</h2>")[0])


@pytest.fixture
def checked(database: Database) -> RunRecord:
    """A run of U5 at line1-st1 whose shift's golden-unit check passed at 07:10; other
    golden runs that are not its reference: another station's, the day before, after it."""
    golden = make_record(serial="GU-001", purpose="golden", started_at=T0 - timedelta(minutes=50))
    others = [
        make_record(serial="GU-002", purpose="golden", station_id="line1-st2", started_at=T0),
        make_record(serial="GU-003", purpose="golden", started_at=T0 - timedelta(days=1)),
        make_record(serial="GU-004", purpose="golden", started_at=T0 + timedelta(minutes=30)),
    ]
    run = make_record(serial="U5", part_number="DIXX-A12", started_at=T0 + timedelta(minutes=5))
    _store(database, golden, *others, run)
    return run


def test_a_certificate_states_what_iso_17025_asks_of_it(
    client: httpx.Client, checked: RunRecord
) -> None:
    page = client.get("/api/v1/units/U5/certificate").text
    block = _identity(page)
    number = f"CAL-2026-{checked.run_id.hex[:12].upper()}"
    assert f'<td id="document-number">{number}</td>' in block
    assert "<tr><th>part number</th><td>DIXX-A12</td></tr>" in block
    assert "08:05:00 UTC" in block  # the run's time in the plant's zone (UTC here)
    assert "<tr><th>station / operator</th><td>line1-st1 / op-17</td></tr>" in block
    assert "1.4.0 / autocal-ls / six" in block
    assert f"sha256 {LIMITS['sha256']}" in block
    reference = block.split('<td class="golden">')[1].split("</td>")[0]
    assert "GU-001" in reference
    assert "07:10:00 UTC" in reference
    assert ", pass (" in reference
    for other in ("GU-002", "GU-003", "GU-004"):
        assert other not in page
    assert "temperature 24.5 … 24.5 °C (the run's poses; mean 24.5 °C)" in block
    method = block.split('<table class="method">')[1]
    for source in ("[Song2006]", "JCGM 100:2008", "ILAC-G8:09/2019"):
        assert source in method
    assert "[Tedaldi2014]" not in method  # a six-parameter run without gyro moves
    assert "<tr><th>decision rule</th><td>simple acceptance" in block


def test_the_limits_table_gives_each_check_its_unit_and_result(
    client: httpx.Client, checked: RunRecord
) -> None:
    page = client.get("/api/v1/units/U5/certificate").text
    limits = page.split('<table class="limits">')[1].split("</table>")[0]
    rows = {
        cells[0]: cells[1:]
        for cells in (re.findall(r"<td[^>]*>(.*?)</td>", row) for row in limits.split("<tr>"))
        if cells
    }
    assert rows["offset"][0] == "counts"
    assert rows["offset"][3] == "x 2081.9, y 2041.2, z 1960.5"
    assert rows["sensitivity"][0] == "counts/g"
    assert rows["verification pose error"][0] == "mg"
    assert rows["verification pose error"][3] == "0.7"
    assert rows["pose noise (std)"][0] == "counts"
    assert rows["gyro bias"][0] == "deg/s"
    assert rows["link loss"][0] == "fraction"
    assert all(cells[4] == "pass" for cells in rows.values())


def test_no_golden_check_that_shift_is_said_and_a_failure_report_has_the_same_identity(
    client: httpx.Client, database: Database
) -> None:
    record = make_record(serial="U6", verdict="fail", failures=[OFFSET_X_HIGH], started_at=T0)
    yesterday = make_record(serial="GU-001", purpose="golden", started_at=T0 - timedelta(days=1))
    _store(database, yesterday, record)
    page = client.get("/api/v1/units/U6/certificate").text
    block = _identity(page)
    assert "<h1>Failure report</h1>" in page
    assert f'<td id="document-number">FR-2026-{record.run_id.hex[:12].upper()}</td>' in block
    assert "<tr><th>part number</th><td>" in block
    assert "no golden-unit check on record for this station that shift" in block
    assert "GU-001" not in page
    assert "[Song2006]" in block
    limits = page.split('<table class="limits">')[1].split("</table>")[0]
    assert re.search(r"<td>offset</td><td>counts</td>.*?<td class=\"fail\">fail</td>", limits)
