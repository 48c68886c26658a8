"""Holds get closed on the pages: a held unit's page lists its reviews and
has a form to review it with a quality key; a refused review answers a page in one line;
the failure report lists the reviews; the report counts the open holds."""

import html
import re
from datetime import timedelta

import httpx

from db import Database, RunRepository
from tests.db.records import T0, make_record

FAILED = {"verdict": "fail", "failures": [{"code": "offset", "message": "offset x high"}]}
FORM = {
    "root_cause": "accel y stuck: cracked solder joint on U3",
    "repair_action": "U3 reflowed",
    "decision": "scrap",
}


def _store(database: Database, serial: str, *outcomes: dict[str, object]) -> list[str]:
    records = [
        make_record(serial=serial, started_at=T0 + timedelta(hours=i), **outcome)
        for i, outcome in enumerate(outcomes)
    ]
    with database.session() as session, session.begin():
        for record in records:
            RunRepository(session).submit(record)
    return [str(r.run_id) for r in records]


def _hidden_run(page: str) -> str:
    found = re.search(r'<input type="hidden" name="run_id" value="([^"]+)">', page)
    assert found is not None, "no review form"
    return found.group(1)


def _text(page: str) -> str:
    return html.unescape(re.sub(r"<[^>]+>", " ", page))


def test_a_held_unit_is_reviewed_from_its_page_and_the_review_shows_on_its_pages(
    client: httpx.Client, database: Database, quality_key: str
) -> None:
    _, latest = _store(database, "PT000410", FAILED, FAILED)
    page = client.get("/units/PT000410")
    assert page.status_code == 200
    assert _hidden_run(page.text) == latest
    assert "No quality review of this unit is stored." in page.text
    answer = client.post(
        "/units/PT000410/reviews", data={**FORM, "run_id": latest, "key": quality_key}
    )
    assert answer.status_code == 303
    assert answer.headers["location"] == "/units/PT000410#reviews"
    stored = client.get("/api/v1/units/PT000410/reviews").json()["data"]
    assert [(r["run_id"], r["reviewer"], r["decision"]) for r in stored] == [
        (latest, "qe-ana", "scrap")
    ]
    page = client.get("/units/PT000410")
    rows = re.findall(r'<tr class="review">(.*?)</tr>', page.text, re.S)
    assert len(rows) == 1
    assert all(part in _text(rows[0]) for part in ("qe-ana", FORM["root_cause"], "scrap"))
    # Scrapped: the page says so, offers nothing next and no form to review it again.
    assert re.search(r'<b id="disposition" class="hold">scrapped</b>', page.text)
    assert '<b id="next">–</b>' in page.text
    assert '<form class="review"' not in page.text
    report = client.get("/api/v1/units/PT000410/certificate")
    assert "Failure report" in report.text
    assert len(re.findall(r'<tr class="review">', report.text)) == 1
    assert FORM["repair_action"] in _text(report.text)


def test_a_passed_unit_has_no_review_form(client: httpx.Client, database: Database) -> None:
    _store(database, "PT000411", FAILED, {})
    page = client.get("/units/PT000411")
    assert page.status_code == 200
    assert 'name="run_id"' not in page.text
    certificate = client.get("/api/v1/units/PT000411/certificate")
    assert 'class="reviews"' not in certificate.text


def test_a_refused_review_answers_a_page_in_one_line(
    client: httpx.Client, database: Database, quality_key: str, station_key: str
) -> None:
    first, latest = _store(database, "PT000412", FAILED, FAILED)
    _store(database, "PT000413", {})
    sent = {**FORM, "run_id": latest}

    def post(serial: str = "PT000412", **change: str) -> httpx.Response:
        return client.post(f"/units/{serial}/reviews", data={**sent, **change})

    for answer, code, line in [
        (post(), 401, "a quality key is required"),
        (post(key="not-a-key"), 401, "unknown or revoked API key"),
        (post(key=station_key), 403, "need a quality key"),
        (post(key=quality_key, run_id=first), 409, "is not the latest run of PT000412"),
        (post("PT000413", key=quality_key), 409, "is not the latest run of PT000413"),
        (post(key=quality_key, root_cause=""), 422, "root_cause"),
        (post(key=quality_key, decision="keep"), 422, "decision"),
    ]:
        assert answer.status_code == code, (code, answer.text)
        assert answer.headers["content-type"].startswith("text/html"), answer.text
        message = re.search(r'<p id="problem"[^>]*>(.*?)</p>', answer.text, re.S)
        assert message is not None, answer.text
        assert line in html.unescape(message.group(1))
        assert "\n" not in message.group(1).strip()
    assert client.get("/api/v1/units/PT000412/reviews").json()["count"] == 0


def test_the_report_counts_open_holds_by_cause_until_reviewed(
    client: httpx.Client, database: Database, quality_key: str
) -> None:
    noise = {"verdict": "fail", "failures": [{"code": "pose_noise", "message": "noisy"}]}
    _store(database, "PT000420", FAILED)
    _store(database, "PT000421", noise)
    (held,) = _store(database, "PT000422", noise)
    _store(database, "PT000423", {})
    report = client.get("/api/v1/reports/eol").json()
    holds = report["open_holds"]
    assert holds["total"] == 3 == report["units_held"]
    assert sum(count["units"] for count in holds["by_age"]) == 3
    assert [(c["label"], c["units"]) for c in holds["by_cause"]] == [
        ("pose_noise", 2),
        ("offset", 1),
    ]
    headers = {"Authorization": f"Bearer {quality_key}"}
    review = {**FORM, "run_id": held, "decision": "retest"}
    posted = client.post("/api/v1/units/PT000422/reviews", json=review, headers=headers)
    assert posted.status_code == 201
    holds = client.get("/api/v1/reports/eol").json()["open_holds"]
    assert holds["total"] == 2
    assert [(c["label"], c["units"]) for c in holds["by_cause"]] == [
        ("offset", 1),
        ("pose_noise", 1),
    ]
    page = client.get("/api/v1/reports/eol", params={"format": "html"}).text
    assert "Open holds (2)" in page
    csv = client.get("/api/v1/reports/eol", params={"format": "csv"}).text
    assert "open_holds,by_cause,pose_noise,1" in csv


def test_a_unit_released_for_a_retest_says_so_and_offers_no_second_review(
    client: httpx.Client, database: Database, quality_key: str
) -> None:
    _, latest = _store(database, "PT000411", FAILED, FAILED)
    form = {**FORM, "decision": "retest", "run_id": latest, "key": quality_key}
    assert client.post("/units/PT000411/reviews", data=form).status_code == 303
    page = client.get("/units/PT000411").text
    assert '<b id="disposition" class="hold">retest</b>' in page
    assert '<b id="next">retest</b>' in page
    assert "Released for a retest by qe-ana" in page
    assert '<form class="review"' not in page
