"""A parameter split by station (and the rest) over a live server: the groups' box plot
figures, Cpk and observed ppm worked out here from the values stored, the page and the
JSON saying the same, a refused split answering a page."""

import html
import re
from datetime import timedelta

import httpx
import numpy as np

from db import Database, RunRepository
from tests.db.records import T0, make_record

#: offset_x per run, by station: st2 has one far value (a Tukey outlier).
VALUES = {
    "line1-st1": [2080.0, 2081.0, 2082.0, 2083.0, 2084.0],
    "line1-st2": [2090.0, 2091.0, 2092.0, 2093.0, 2420.0],
}


def _store(database: Database) -> None:
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        for s, (station, values) in enumerate(VALUES.items()):
            for i, value in enumerate(values):
                repository.submit(
                    make_record(
                        serial=f"PT{s}{i:05d}",
                        station_id=station,
                        started_at=T0 + timedelta(minutes=10 * i + s),
                        offset=(value, 2041.2, 1960.5),
                        lot=f"lot-{i % 2}",
                    )
                )


def test_a_split_by_station_has_each_groups_figures_from_its_values(
    client: httpx.Client, database: Database
) -> None:
    _store(database)
    answer = client.get(
        "/api/v1/reports/split", params={"parameter": "offset_x", "by": "station", "format": "json"}
    )
    assert answer.status_code == 200, answer.text
    split = answer.json()
    assert split["sampled_runs"] == 10
    lower, upper = split["lower"], split["upper"]
    assert (lower, upper) != (None, None), split["bounds_source"]
    groups = {g["group"]: g for g in split["groups"]}
    assert set(groups) == set(VALUES)
    for station, values in VALUES.items():
        g, data = groups[station], np.array(values)
        q1, median, q3 = np.percentile(data, [25, 50, 75])
        fences = (q1 - 1.5 * (q3 - q1), q3 + 1.5 * (q3 - q1))
        inside = data[(data >= fences[0]) & (data <= fences[1])]
        out = sum(
            1
            for v in values
            if (lower is not None and v < lower) or (upper is not None and v > upper)
        )
        assert g["n"] == len(values)
        assert np.isclose(g["mean"], data.mean())
        assert np.isclose(g["sd"], data.std(ddof=1))
        assert (g["q1"], g["median"], g["q3"]) == (q1, median, q3)
        assert (g["whisker_low"], g["whisker_high"]) == (inside.min(), inside.max())
        assert g["outliers"] == len(values) - len(inside)
        assert g["out_of_limits"] == out
        assert np.isclose(g["ppm_observed"], 1e6 * out / len(values))
    assert groups["line1-st2"]["outliers"] == 1
    assert groups["line1-st1"]["outliers"] == 0
    page = client.get("/api/v1/reports/split", params={"parameter": "offset_x", "by": "station"})
    assert page.status_code == 200
    assert page.headers["content-type"].startswith("text/html")
    assert page.text.count('<rect class="box"') == 2
    assert "From the latest 10 runs" in html.unescape(re.sub(r"\s+", " ", page.text))
    rows = re.findall(r'<tr class="group"><td><a [^>]+>([^<]+)</a></td><td>(\d+)</td>', page.text)
    assert sorted(rows) == [(s, str(len(v))) for s, v in sorted(VALUES.items())]
    by_lot = client.get(
        "/api/v1/reports/split", params={"parameter": "offset_x", "by": "lot", "format": "json"}
    ).json()
    assert {g["group"]: g["n"] for g in by_lot["groups"]} == {"lot-0": 6, "lot-1": 4}
    narrowed = client.get(
        "/api/v1/reports/split",
        params={"parameter": "offset_x", "by": "lot", "station": "line1-st1", "format": "json"},
    ).json()
    assert sum(g["n"] for g in narrowed["groups"]) == len(VALUES["line1-st1"])


def test_a_group_of_a_split_opens_the_report_of_its_runs(
    client: httpx.Client, database: Database
) -> None:
    _store(database)
    for by, counts in (
        ("station", {station: len(values) for station, values in VALUES.items()}),
        ("lot", {"lot-0": 6, "lot-1": 4}),
    ):
        page = client.get("/api/v1/reports/split", params={"parameter": "offset_x", "by": by})
        links = re.findall(r'<tr class="group"><td><a href="([^"]+)">([^<]+)</a>', page.text)
        assert sorted(group for _, group in links) == sorted(counts)
        for link, group in links:
            opened = client.get(html.unescape(link))
            assert opened.status_code == 200, opened.text
            assert opened.headers["content-type"].startswith("text/html")
            report = client.get(html.unescape(link).replace("format=html", "format=json"))
            assert report.json()["summary"]["runs"] == counts[group], (by, group)


def test_a_refused_split_answers_a_page_and_no_runs_say_so(
    client: httpx.Client, database: Database
) -> None:
    bad = client.get("/api/v1/reports/split", params={"parameter": "colour", "by": "station"})
    assert bad.status_code == 422
    assert bad.headers["content-type"].startswith("text/html")
    assert 'id="problem"' in bad.text
    wrong = client.get("/api/v1/reports/split", params={"parameter": "offset_x", "by": "moon"})
    assert wrong.status_code == 422
    empty = client.get(
        "/api/v1/reports/split", params={"parameter": "gyro_bias_z", "by": "operator"}
    )
    assert empty.status_code == 200
    assert 'id="no-runs"' in empty.text


def test_a_split_by_fixture_slot_groups_the_runs_by_their_recorded_slot(
    client: httpx.Client, database: Database
) -> None:
    #: (offset_x, slot) per run; None: a run recorded before slots were.
    runs = [(2080.0, 1), (2082.0, 2), (2081.0, 1), (2095.0, 2), (2084.0, 2), (2083.0, None)]
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        for i, (value, slot) in enumerate(runs):
            repository.submit(
                make_record(
                    serial=f"PT{i:06d}",
                    started_at=T0 + timedelta(minutes=10 * i),
                    offset=(value, 2041.2, 1960.5),
                    fixture_slot=slot,
                )
            )
    split = client.get(
        "/api/v1/reports/split",
        params={"parameter": "offset_x", "by": "fixture_slot", "format": "json"},
    ).json()
    groups = {g["group"]: (g["n"], g["mean"]) for g in split["groups"]}
    expected: dict[str, list[float]] = {}
    for value, slot in runs:
        expected.setdefault("(none)" if slot is None else str(slot), []).append(value)
    assert set(groups) == set(expected)
    for name, values in expected.items():
        assert groups[name][0] == len(values)
        assert np.isclose(groups[name][1], np.mean(values))
    page = client.get(
        "/api/v1/reports/split", params={"parameter": "offset_x", "by": "fixture_slot"}
    ).text
    assert '<option value="fixture_slot" selected>fixture slot</option>' in page
