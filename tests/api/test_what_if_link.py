"""A what-if's result names the units whose verdict would flip, and, run with a quality
key, has a link that answers it again (the candidate profile kept by its SHA-256), on a
live server; run without one, it stores nothing."""

import re
from importlib import resources

import httpx
import pytest
from sqlalchemy import func, select

from db import Database
from db.models import StoredLimitsProfile
from tests.db.eol_data import RUNS, insert_line_history

RANGE = {"from": "2026-11-02T08:00:00Z", "to": "2026-11-02T10:00:00Z"}
SHIPPED = "offset_counts = { lower = 1841.0, upper = 2255.0 }"


def _candidate(upper: float) -> str:
    """The shipped limits file with the production offsets' upper limit at ``upper``."""
    text = resources.files("station.domain.profiles").joinpath("limits.toml").read_text("utf-8")
    assert SHIPPED in text
    return (
        text.replace("[profiles.kxm52-production]", "[profiles.candidate]")
        .replace('version = "1"', 'version = "2"', 1)
        .replace(SHIPPED, f"offset_counts = {{ lower = 1841.0, upper = {upper} }}", 1)
    )


def _expected_flips(upper: float) -> list[tuple[str, str, str, str]]:
    """From the raw history: each unit whose first run is in range, its latest run's
    verdict as stored and under offsets within 1841…``upper`` (z is 1960.5 in every run;
    its other stored reasons pass on their values), and the deciding check."""
    first = {serial: minute for minute, serial, *_ in reversed(RUNS)}
    latest = {serial: (code, (x, y)) for _, serial, _, _, code, x, y in RUNS}
    flips = []
    for serial in sorted(s for s, minute in first.items() if minute < 120):
        code, offsets = latest[serial]
        before = "fail" if code else "pass"
        passes = all(1841.0 <= v <= upper for v in (*offsets, 1960.5))
        after = "pass" if passes else "fail"
        if before != after:
            flips.append((serial, before, after, code if passes else "offset"))
    return flips


@pytest.mark.parametrize("upper", [2046.0, 2053.0])
def test_a_what_if_lists_the_flipped_units_and_its_link_answers_it_again(
    client: httpx.Client, database: Database, quality_key: str, upper: float
) -> None:
    with database.session() as session:
        insert_line_history(session)
    expected = _expected_flips(upper)
    assert expected  # the narrower candidate fails passing units, the wider passes a failed one
    upload = {"limits": ("candidate.toml", _candidate(upper).encode())}
    which = {"profile": "candidate", "key": quality_key}
    answer = client.post(
        "/api/v1/reports/eol", params={**RANGE, "format": "json"}, files=upload, data=which
    )
    assert answer.status_code == 200, answer.text
    what_if = answer.json()["what_if"]
    flips = [(f["serial"], f["before"], f["after"], f["check"]) for f in what_if["flips"]]
    assert flips == expected
    assert what_if["flips_total"] == len(expected)
    assert what_if["kept"] is True

    page = client.post("/api/v1/reports/eol", params=RANGE, files=upload, data=which).text
    table = page.split('<table class="flips">', 1)[1].split("</table>", 1)[0]
    for serial, before, after, check in expected:
        assert f'<a class="serial" href="/units/{serial}">{serial}</a>' in table
        assert f'<span class="{before}">{before}</span> → <span class="{after}">{after}' in table
        assert f"<td>{check}</td>" in table
    found = re.search(r'id="what-if-link" href="([^"]+)"', page)
    assert found is not None
    link = found.group(1).replace("&amp;", "&")
    assert what_if["limits"]["sha256"] in link
    again = client.get(link)
    assert again.status_code == 200, again.text
    assert table in again.text
    as_json = client.get(link.replace("format=html", "format=json"))
    assert as_json.json()["what_if"] == what_if


def test_a_link_to_a_what_if_never_stored_is_refused_in_one_line(client: httpx.Client) -> None:
    unknown = "0" * 64
    answer = client.get("/api/v1/reports/eol", params={"what_if": unknown, "format": "json"})
    assert answer.status_code == 422
    assert answer.json()["errors"][0]["loc"] == "query.what_if"
    page = client.get("/api/v1/reports/eol", params={"what_if": unknown, "format": "html"})
    assert page.status_code == 422
    assert f"no stored limits profile {unknown}" in page.text
    # An empty field of a form is no what-if, as every empty filter field.
    plain = client.get("/api/v1/reports/eol", params={"what_if": "", "format": "json"})
    assert plain.status_code == 200, plain.text
    assert plain.json()["what_if"] is None


def _profiles(database: Database) -> int:
    with database.session() as session:
        return int(session.scalar(select(func.count()).select_from(StoredLimitsProfile)) or 0)


def test_an_anonymous_what_if_is_answered_and_stores_nothing(
    client: httpx.Client, database: Database, station_key: str
) -> None:
    with database.session() as session:
        insert_line_history(session)
    before = _profiles(database)
    for upper in (2046.0, 2047.0, 2048.0):
        upload = {"limits": ("candidate.toml", _candidate(upper).encode())}
        answer = client.post(
            "/api/v1/reports/eol", params=RANGE, files=upload, data={"profile": "candidate"}
        )
        assert answer.status_code == 200, answer.text
        assert 'id="what-if-link"' not in answer.text
        assert "Nothing was stored: run it with a quality key" in answer.text
    assert _profiles(database) == before
    upload = {"limits": ("candidate.toml", _candidate(2046.0).encode())}
    for key, status, words in (
        (station_key, 403, "this API key belongs to station line1-st1: reviews of units"),
        ("csk_not-a-key", 401, "unknown or revoked API key"),
    ):
        refused = client.post(
            "/api/v1/reports/eol",
            params={**RANGE, "format": "json"},
            files=upload,
            data={"profile": "candidate", "key": key},
        )
        assert refused.status_code == status, refused.text
        assert words in refused.json()["detail"]
    assert _profiles(database) == before
