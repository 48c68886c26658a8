"""The quality engineer's pages agree with themselves: one time zone per page,
a filtered report that counts the units it lists, failure reasons as stored, forms that
answer pages, definitions that hold across pages; on a server in the plant's zone
(Europe/Berlin), on both backends."""

import html
import re
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from zoneinfo import ZoneInfo

import httpx
import numpy as np
import pytest

from db import Database, RunRepository
from station.domain.record.records import RunRecord
from tests.db.records import OUTCOMES, T0, make_record
from tests.servers import local_client, serving

ZONE = "Europe/Berlin"


@pytest.fixture(scope="module")
def plant_url(migrated_database: Database, database_url: str) -> Iterator[str]:
    """A server whose plant is in Berlin (CET in November: UTC+1)."""
    with serving(database_url, plant_timezone=ZONE) as base:
        yield base


@pytest.fixture
def plant(database: Database, plant_url: str) -> Iterator[httpx.Client]:
    """A client of the plant's server; the database is emptied after the test."""
    with local_client(plant_url, timeout=30) as client:
        yield client


def store(database: Database, *records: RunRecord) -> None:
    with database.session() as session:
        repository = RunRepository(session)
        for record in records:
            repository.submit(record)
        session.commit()


def _times(html: str) -> list[str]:
    """Every moment printed to the second on a page, with its zone's abbreviation."""
    return re.findall(r"\d{4}-\d\d-\d\d \d\d:\d\d:\d\d [A-Z]+", html)


def test_every_page_prints_times_in_the_plants_zone(
    plant: httpx.Client, database: Database
) -> None:
    now = datetime.now(UTC).replace(microsecond=0)
    store(
        database,
        make_record(serial="U1", verdict="fail", started_at=T0),
        make_record(serial="U1", started_at=T0 + timedelta(minutes=5)),
        make_record(serial="U2", verdict="fail", started_at=now - timedelta(minutes=2)),
    )
    unit = plant.get("/units/U1").text
    certificate = plant.get("/api/v1/units/U1/certificate").text
    failure = plant.get("/api/v1/units/U2/certificate").text
    report = plant.get(
        "/api/v1/reports/eol", params={"format": "html", "list": "all", "from": "2026-11-02"}
    ).text
    dashboard = plant.get("/").text
    # 08:00 UTC is 09:00 CET: the unit page, its certificate and the report's list agree
    assert "2026-11-02 09:00:00 CET" in unit
    assert "2026-11-02 09:05:00 CET" in certificate  # the run certified
    assert "2026-11-02 09:00:00 CET" in certificate  # its earlier run
    assert "2026-11-02 09:05:00 CET" in report.split('<table class="units">')[1]
    local = (now - timedelta(minutes=2)).astimezone(ZoneInfo(ZONE))
    stamp = local.strftime("%Y-%m-%d %H:%M:%S %Z")
    assert stamp in failure
    assert stamp in dashboard.split('<table class="units">')[1]
    for name, page in {
        "unit": unit,
        "certificate": certificate,
        "failure report": failure,
        "report": report,
        "dashboard": dashboard,
    }.items():
        printed = _times(page)
        assert printed, name
        assert {t.rsplit(" ", 1)[1] for t in printed} <= {"CET", "CEST"}, (name, printed)


ST1, ST2 = "line1-st1", "line1-st2"
DAY = timedelta(days=1)


def _filtered_history(database: Database) -> None:
    """Units whose first run is in the period at line1-st1 (A, B, C, F) beside units whose
    latest run is there but whose first is not (D: first at st2; E: first the day before),
    and units whose latest run is elsewhere (A) or after the period (B, F)."""
    hour = timedelta(hours=1)
    store(
        database,
        make_record(serial="A", station_id=ST1, verdict="fail", started_at=T0),
        make_record(serial="A", station_id=ST2, started_at=T0 + hour / 6),
        make_record(serial="B", station_id=ST1, verdict="fail", started_at=T0 + hour),
        make_record(serial="B", station_id=ST1, verdict="fail", started_at=T0 + DAY),
        make_record(serial="C", station_id=ST1, started_at=T0 + 2 * hour),
        make_record(serial="D", station_id=ST2, verdict="fail", started_at=T0),
        make_record(serial="D", station_id=ST1, started_at=T0 + 3 * hour),
        make_record(serial="E", station_id=ST1, verdict="fail", started_at=T0 - DAY),
        make_record(serial="E", station_id=ST1, verdict="fail", started_at=T0 + 5 * hour),
        make_record(serial="F", station_id=ST1, started_at=T0 + 4 * hour),
        make_record(serial="F", station_id=ST2, verdict="fail", started_at=T0 + DAY),
    )


def test_a_filtered_report_lists_the_units_its_yield_table_counts(
    plant: httpx.Client, database: Database
) -> None:
    _filtered_history(database)
    period = {"from": "2026-11-02", "to": "2026-11-03", "station": ST1}
    everything = plant.get("/api/v1/reports/eol", params={**period, "list": "all"}).json()
    held = plant.get("/api/v1/reports/eol", params={**period, "list": "held"}).json()
    summary = everything["summary"]
    listed = {u["serial"] for u in everything["units"]}
    on_hold = {u["serial"] for u in held["units"]}
    assert listed == {"A", "B", "C", "F"}
    assert on_hold == {"B", "F"}
    assert (summary["units_tested"], summary["units_failed"]) == (len(listed), len(on_hold))
    assert (everything["units_total"], held["units_held"]) == (len(listed), len(on_hold))
    # each row is the unit's latest run, even when it is elsewhere or after the period
    rows = {u["serial"]: u for u in everything["units"]}
    assert (rows["A"]["station_id"], rows["A"]["disposition"]) == (ST2, "ship")
    assert (rows["F"]["station_id"], rows["F"]["disposition"]) == (ST2, "hold")
    assert rows["B"]["last_started_at"].startswith("2026-11-03")
    page = plant.get("/api/v1/reports/eol", params={**period, "format": "html"}).text
    rule = page.split('class="definition units-rule">')[1].split("</p>")[0]
    for words in ("first run", f"station {ST1}", "latest run"):
        assert words in rule
    assert f"of {len(on_hold)} held" in page


#: Pose noise over its one-sided limit, as the station words and records it.
POSE_NOISE = {
    "code": "pose_noise",
    "message": "pose noise x (pose 3) 8.59057 counts",
    "measured": 8.59057,
    "upper": 8.0,
    "axis": "x",
    "pose": 3,
}


def test_failure_reasons_read_as_the_station_stored_them(
    plant: httpx.Client, database: Database
) -> None:
    store(
        database,
        make_record(serial="N1", verdict="fail", failures=[POSE_NOISE], started_at=T0),
        make_record(serial="N1", started_at=T0 + timedelta(minutes=3)),
    )
    unit = plant.get("/units/N1").text
    certificate = plant.get("/api/v1/units/N1/certificate").text
    earlier = certificate.split("<h2>Earlier runs</h2>")[1]
    shown = "pose noise x (pose 3) 8.59057 counts (measured 8.59057, limit ≤ 8)"
    assert shown in unit
    assert shown in earlier
    for page in (unit, earlier):
        assert "(– …" not in page
        assert "pose_noise " not in page  # not a bare code


def _problem(answer: httpx.Response) -> str:
    """The one-line message of a refused page, after checking it is a page."""
    assert answer.status_code == 422
    assert answer.headers["content-type"].startswith("text/html")
    found = re.search(r'<p id="problem" class="problem">([^<]*)</p>', answer.text)
    assert found is not None, answer.text
    assert "\n" not in found[1].strip()
    return html.unescape(found[1])


def test_a_bad_filter_on_a_page_answers_a_page_and_json_stays_json(
    plant: httpx.Client,
) -> None:
    report = "/api/v1/reports/eol"
    typed = _problem(plant.get(report, params={"format": "html", "from": "14.11.2026"}))
    assert "from '14.11.2026' is not an ISO date" in typed
    assert "write 2026-11-14" in typed
    # the form comes back with what was typed, to correct it
    answer = plant.get(report, params={"format": "html", "from": "14.11.2026", "lot": "L7"})
    assert 'name="from" type="date" value="14.11.2026"' in answer.text
    assert 'name="lot" value="L7"' in answer.text
    assert "units" in _problem(plant.get(report, params={"format": "html", "units": "0"}))
    order = _problem(
        plant.get(report, params={"format": "html", "from": "2026-11-03", "to": "2026-11-02"})
    )
    assert "is not before to" in order
    # the JSON answers are unchanged: 422 naming the field
    for params in ({"from": "14.11.2026"}, {"format": "json", "from": "14.11.2026"}):
        data = plant.get(report, params=params)
        assert data.status_code == 422
        assert data.json()["errors"][0]["loc"] == "query.from"
    # a what-if file that is not one: the form's page (HTML by default), or JSON asked for
    bad = {"limits": ("bad.toml", b"[profiles.x]\noffset = 3")}
    assert "bad.toml" in _problem(plant.post(report, files=bad))
    as_json = plant.post(report, params={"format": "json"}, files=bad)
    assert as_json.json()["errors"][0]["loc"] == "body.limits"


def test_the_report_form_picks_dates_and_says_when_no_run_matches(
    plant: httpx.Client, database: Database
) -> None:
    store(database, make_record(serial="M1", started_at=T0))
    report = "/api/v1/reports/eol"
    page = plant.get(report, params={"format": "html"}).text
    assert '<input name="from" type="date" value=""' in page
    assert "placeholder" not in page.split('<form class="filters"')[1].split("</form>")[0]
    assert 'id="no-runs"' not in page
    assert "<svg" in page
    for params in ({"station": "no-such-station"}, {"from": "2030-01-01"}):
        empty = plant.get(report, params={"format": "html", **params})
        assert empty.status_code == 200
        assert 'id="no-runs"' in empty.text
        assert "No runs match" in empty.text
        assert "<svg" not in empty.text  # no empty charts
    assert (
        "station no-such-station"
        in plant.get(report, params={"format": "html", "station": "no-such-station"}).text.split(
            'id="no-runs"'
        )[1]
    )


def _cells(page: str, table: str, row: str) -> dict[str, str]:
    """The cells of the row named ``row`` of ``<table class="{table}">``, by header."""
    body = page.split(f'<table class="{table}">')[1].split("</table>")[0]
    header = re.findall(r"<th>([^<]*)</th>", body)
    for cells in re.findall(r"<tr>((?:<td[^>]*>.*?</td>)+)</tr>", body):
        values = re.findall(r"<td[^>]*>(.*?)</td>", cells)
        if values[0] == row:
            return dict(zip(header, values, strict=True))
    raise AssertionError(f"no row {row} in {table}")


def test_aborts_are_no_failures_retests_or_holds_and_units_per_hour_agree(
    plant: httpx.Client, database: Database
) -> None:
    now = datetime.now(UTC)
    midnight = datetime.combine(now.astimezone(ZoneInfo(ZONE)).date(), datetime.min.time())
    start = max(midnight.replace(tzinfo=ZoneInfo(ZONE)), now - timedelta(minutes=5))
    at = [start + timedelta(seconds=10 * i) for i in range(6)]
    store(
        database,
        make_record(serial="P1", started_at=at[0]),
        make_record(serial="P2", started_at=at[1], **OUTCOMES["aborted"]),
        make_record(serial="P2", started_at=at[2]),
        make_record(serial="P3", started_at=at[3], **OUTCOMES["aborted"]),
        make_record(serial="P4", verdict="fail", started_at=at[4]),
    )
    today = {"from": midnight.date().isoformat()}
    report = plant.get("/api/v1/reports/eol", params={**today, "list": "all"}).json()
    s = report["summary"]
    # P3 was never attempted; P2's abort is no retest; no abort in the Pareto
    assert (s["runs"], s["aborted_runs"], s["retests"]) == (5, 2, 0)
    assert (s["units_tested"], s["units_failed"]) == (3, 1)
    assert [e["code"] for e in report["pareto"]] == ["sensitivity_out_of_range"]
    assert {u["serial"] for u in report["units"]} == {"P1", "P2", "P4"}
    dashboard = plant.get("/").text
    held = dashboard.split('<table class="held">')[1].split("</table>")[0]
    assert "/units/P4" in held
    assert "/units/P3" not in held
    # units per hour: per hour of station time (95 s a run), the same on both pages
    assert s["units_per_hour"] == pytest.approx(3600 * 3 / (5 * 95))
    tile = re.search(r'<b id="units-per-hour">([^<]*)</b>', dashboard)
    assert tile is not None
    page = plant.get("/api/v1/reports/eol", params={**today, "format": "html"}).text
    assert tile[1] == _cells(page, "summary", "all")["units/h"]
    assert _cells(dashboard, "summary", "all")["units/h"] == tile[1]


def _chart(page: str, title: str) -> str:
    """The inline SVG whose title is ``title``."""
    for svg in re.findall(r"<svg.*?</svg>", page, flags=re.S):
        if f"<title>{title}</title>" in svg:
            return str(svg)
    raise AssertionError(f"no chart {title!r}")


def test_histograms_bin_the_data_and_capability_shows_observed_ppm(
    plant: httpx.Client, database: Database
) -> None:
    # gyro bias z: 200 units tightly around 0.5 deg/s, and 3 far beyond the +10 limit
    biases = [0.5 + 0.002 * ((i * 37) % 200 - 100) for i in range(200)] + [14.0] * 3
    store(
        database,
        *(
            make_record(
                serial=f"G{i}",
                started_at=T0 + timedelta(minutes=i),
                gyro={
                    "bias": {"x": 0.01, "y": -0.02, "z": z},
                    "noise": {"x": 0.05, "y": 0.05, "z": 0.06},
                },
            )
            for i, z in enumerate(biases)
        ),
    )
    period = {"from": "2026-11-02", "to": "2026-11-04"}
    report = plant.get("/api/v1/reports/eol", params=period).json()
    z = next(p for p in report["parameters"] if p["name"] == "gyro_bias_z")
    assert z["out_of_limits"] == 3
    assert z["observed_ppm"] == pytest.approx(3 / 203 * 1e6)
    assert z["cpk"] >= 1.33  # normal theory calls it capable …
    assert "not one normal population" in z["warning"]  # … and the report says why not
    d = z["distribution"]
    # the three far-out values are counted apart; the rest fill bins of their own width
    assert (d["values"], d["above"], d["below"], sum(d["counts"])) == (203, 3, 0, 200)
    assert len(d["counts"]) > 5  # not the limits' 2–3 bins
    assert d["edges"][-1] < 14.0
    assert d["counts"] == np.histogram(biases[:200], bins=d["edges"])[0].tolist()
    assert d["mean"] == pytest.approx(float(np.mean(biases)))
    page = plant.get("/api/v1/reports/eol", params={**period, "format": "html"}).text
    warning = page.split('class="problem capability-warning">')[1].split("</p>")[0]
    assert html.unescape(warning) == f"gyro_bias_z: {z['warning']}"
    korean = plant.get("/api/v1/reports/eol", params={**period, "format": "html", "lang": "ko"})
    warned = korean.text.split('class="problem capability-warning">')[1].split("</p>")[0]
    assert warned.startswith("gyro_bias_z: 값 203개 중 3개가 한계 밖")
    assert "not one normal population" not in warned
    chart = _chart(page, "histogram of gyro_bias_z")
    bars = re.search(r'<path class="bars" [^>]*d="([^"]+)"', chart)
    assert bars is not None
    assert bars[1].count("M") >= 5  # a box per bin that holds values
    assert ">count<" in chart
    assert "x̄ " in chart
    assert "USL 10" in chart
    assert "3 above →" in chart
    parameters = _cells(page, "parameters", "gyro_bias_z")
    assert parameters["ppm out"] == f"{3 / 203 * 1e6:.4g}"


def test_the_yield_axes_zoom_on_the_yields(plant: httpx.Client, database: Database) -> None:
    # day 1: 3 of 4 units pass first time; day 2: all 4
    day = timedelta(days=1)
    store(
        database,
        *(
            make_record(
                serial=f"Y{d}{i}",
                verdict="fail" if (d, i) == (0, 0) else "pass",
                started_at=T0 + d * day + timedelta(minutes=i),
            )
            for d in range(2)
            for i in range(4)
        ),
    )
    page = plant.get(
        "/api/v1/reports/eol", params={"from": "2026-11-02", "to": "2026-11-04", "format": "html"}
    ).text
    chart = _chart(page, "yield per day")
    labels = re.findall(r">(\d+\.\d) %<", chart)
    assert "0.0" not in labels  # not drawn from 0
    assert labels[:2] == ["100.0", "70.0"]  # the axis' range, from the 5 % step below 75 %


def test_a_search_box_on_every_page_finds_a_unit_by_serial(
    plant: httpx.Client, database: Database
) -> None:
    store(
        database,
        *(make_record(serial=s, started_at=T0) for s in ("PT-0001", "PT-0002", "Q_1", "QX1")),
    )
    pages = [
        "/",
        "/units/PT-0001",
        "/units/NOPE-9",
        "/api/v1/units/PT-0001/certificate",
        "/api/v1/reports/eol?format=html",
        "/api/v1/reports/eol?format=html&from=14.11.2026",
    ]
    for page in pages:
        assert 'action="/search"' in plant.get(page).text, page

    def search(text: str) -> httpx.Response:
        return plant.get("/search", params={"serial": text}, follow_redirects=False)

    exact = search(" PT-0002 ")  # as pasted
    assert (exact.status_code, exact.headers["location"]) == (303, "/units/PT-0002")
    assert search("Q_").headers["location"] == "/units/Q_1"  # _ is itself, not any letter
    several = search("PT-")
    assert several.status_code == 200
    assert re.findall(r'href="/units/([^"]+)"', several.text) == ["PT-0001", "PT-0002"]
    missing = search("ZZ")
    assert missing.status_code == 404
    assert "No unit's serial number begins with ZZ." in html.unescape(missing.text)
    bad = search("a b")
    assert bad.status_code == 422
    assert bad.headers["content-type"].startswith("text/html")
    assert "serial" in _problem(bad)
    followed = plant.get("/search", params={"serial": "PT-0001"}, follow_redirects=True)
    assert (followed.status_code, followed.url.path) == (200, "/units/PT-0001")


def test_a_pareto_bar_opens_the_runs_behind_it(plant: httpx.Client, database: Database) -> None:
    store(
        database,
        make_record(serial="R1", verdict="fail", failures=[POSE_NOISE], started_at=T0),
        make_record(
            serial="R2", verdict="fail", failures=[POSE_NOISE], started_at=T0 + timedelta(hours=1)
        ),
        make_record(serial="R3", verdict="fail", started_at=T0 + timedelta(hours=2)),
        make_record(
            serial="R4",
            station_id="line1-st2",
            verdict="fail",
            failures=[POSE_NOISE],
            started_at=T0 + timedelta(hours=3),
        ),
    )
    period = {"from": "2026-11-02", "to": "2026-11-03", "station": "line1-st1"}
    page = plant.get("/api/v1/reports/eol", params={**period, "format": "html"}).text
    pareto = _chart(page, "failure Pareto: runs per first failure reason")
    links = dict(
        (code, html.unescape(href))
        for href, code in re.findall(r'<a class="runs" href="([^"]+)"><text[^>]*>([^<]+)<', pareto)
    )
    assert set(links) == {"pose_noise", "sensitivity_out_of_range"}
    # the cumulative line keeps clear of the bars' counts
    line = re.search(r'<polyline class="cumulative" points="([^"]+)"', pareto)
    assert line is not None
    reach = max(float(point.split(",")[0]) for point in line[1].split())
    counts = [float(x) for x in re.findall(r'<text x="([\d.]+)"[^>]*>\d+ \(', pareto)]
    assert len(counts) == 2
    assert min(counts) > reach
    # the bar's count is the number of runs its page lists, under the same filter
    runs = plant.get(links["pose_noise"])
    assert runs.status_code == 200
    listed = re.findall(
        r'href="/units/([^"]+)"', runs.text.split('<table class="failing-runs">')[1]
    )
    assert listed == ["R2", "R1"]  # latest first; R4 is at another station
    report = plant.get("/api/v1/reports/eol", params=period).json()
    bars = {e["code"]: e["count"] for e in report["pareto"]}
    assert bars["pose_noise"] == len(listed)
    assert f'href="{links["pose_noise"].replace("&", "&amp;")}">pose_noise</a></td>' in page
    assert "pose noise x (pose 3) 8.59057 counts" in runs.text
    none = plant.get(
        "/api/v1/reports/eol/failures", params={**period, "code": "no_such_reason"}
    ).text
    assert 'id="no-runs"' in none
    bad = plant.get("/api/v1/reports/eol/failures", params={"code": "x y"})
    assert bad.status_code == 422
    assert "code" in _problem(bad)


def test_a_rule_number_on_a_control_chart_stays_legible_over_the_lines(
    plant: httpx.Client, database: Database
) -> None:
    xs = [2080.0 + (i % 3) for i in range(20)] + [2150.0]  # the last beyond 3σ: rule 1
    store(
        database,
        *(
            make_record(
                serial=f"C{i}", offset=(x, 2041.2, 1960.5), started_at=T0 + timedelta(minutes=i)
            )
            for i, x in enumerate(xs)
        ),
    )
    page = plant.get("/api/v1/reports/eol", params={"from": "2026-11-02", "format": "html"}).text
    chart = _chart(page, f"I-MR chart of offset_x, {len(xs)} of {len(xs)} runs plotted")
    rule = re.search(r'<text class="rule" ([^>]*)>1</text>', chart)
    assert rule is not None
    assert 'paint-order="stroke"' in rule[1]
    assert 'stroke="#fff"' in rule[1]


def test_the_report_page_exports_its_filtered_runs_as_csv(
    plant: httpx.Client, database: Database
) -> None:
    _filtered_history(database)
    period = {"from": "2026-11-02", "to": "2026-11-03", "station": ST1}
    page = plant.get("/api/v1/reports/eol", params={**period, "format": "html"}).text
    found = re.search(r'<a id="runs-csv" href="([^"]+)"', page)
    assert found is not None
    export = plant.get(html.unescape(found[1]))
    assert export.status_code == 200
    assert export.headers["content-type"].startswith("text/csv")
    rows = export.text.strip().splitlines()[1:]
    # the runs of the period at the station: A, B, C, D's retest, E's retest, F
    assert len(rows) == 6
    assert all(f",{ST1}," in row for row in rows)
