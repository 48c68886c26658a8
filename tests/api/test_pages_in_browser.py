"""The report page, the dashboard and a certificate in a real headless Chromium.

Each page is served by the live server, loaded by Chromium, checked for its charts and
for console errors, and saved as a screenshot under ``artifacts/``.
"""

from datetime import UTC, datetime, timedelta
from pathlib import Path

import httpx
import pytest

from db import Database, RunRepository
from tests.browser import OFFLINE, Browser, chromium
from tests.db.eol_data import insert_line_history
from tests.db.records import make_record
from tests.servers import HUNG_SERVER_S, local_get

COUNT_CHARTS = "document.querySelectorAll('svg.chart').length"
DRAWN_CHARTS = (
    "Array.from(document.querySelectorAll('svg.chart'))"
    ".filter(s => s.getBoundingClientRect().width > 100).length"
)


def _today(database: Database) -> None:
    """Runs of the last hour at two stations, some failing, some retested."""
    now = datetime.now(UTC).replace(microsecond=0)
    start = max(now - timedelta(hours=1), now.replace(hour=0, minute=0, second=0))
    step = (now - start) / 24
    with database.session() as session:
        repository = RunRepository(session)
        for i in range(24):
            repository.submit(
                make_record(
                    serial=f"PT-{100 + i % 18:06d}",
                    station_id=f"line1-st{1 + i % 2}",
                    verdict="fail" if i % 5 == 3 else "pass",
                    started_at=start + i * step,
                    offset=(2080.0 + (i * 7) % 11, 2041.0 - (i * 3) % 5, 1960.5 + i % 4),
                    sensitivity=(813.9 + (i % 3) * 0.4, 815.6, 818.9 + (i % 2) * 0.5),
                )
            )
        session.commit()


def _check(browser: Browser, url: str, name: str, charts: int) -> None:
    load = browser.load(url)
    assert load.errors == []
    assert browser.evaluate(COUNT_CHARTS) == charts
    assert browser.evaluate(DRAWN_CHARTS) == charts
    assert browser.screenshot(name).stat().st_size > 10_000


def test_report_page_renders_every_chart(
    browser: Browser, live_url: str, database: Database
) -> None:
    with database.session() as session:
        insert_line_history(session)
    url = f"{live_url}/api/v1/reports/eol?format=html&from=2026-11-02&to=2026-11-03"
    # the Pareto, 13 histograms, 6 control charts; the trend: units, yields and the Cpk
    # of the two parameters that vary in the history (offset_x, offset_y)
    _check(browser, url, f"eol-report-{database.engine.dialect.name}", charts=20 + 2 + 2)
    # the Pareto's bars, and a path of bars in each histogram
    assert browser.evaluate("document.querySelectorAll('rect.bar').length") >= 3
    assert browser.evaluate("document.querySelectorAll('path.bars').length") >= 13
    # the held units: U3 and U5
    assert browser.evaluate("document.querySelectorAll('table.units tr').length") == 1 + 2


def test_dashboard_renders_today(browser: Browser, live_url: str, database: Database) -> None:
    _today(database)
    _check(browser, f"{live_url}/", f"dashboard-{database.engine.dialect.name}", charts=7)
    assert browser.evaluate("document.getElementById('units-tested').textContent") == "18"
    points = "document.querySelectorAll('g.point > circle, circle.point')"
    assert browser.evaluate(f"{points}.length") == 6 * 24


def test_certificate_page_renders(browser: Browser, live_url: str, database: Database) -> None:
    with database.session() as session:
        insert_line_history(session)
    _check(
        browser,
        f"{live_url}/api/v1/units/U2/certificate",
        f"certificate-{database.engine.dialect.name}",
        charts=0,
    )
    assert browser.evaluate("document.querySelectorAll('table.poses tr').length") == 1 + 7


# -- drill-down: serial links, unit pages, failure reports ----------------------------

#: Every serial link of the page, fetched from the page: [href, status, the page's h1].
FETCH_SERIAL_LINKS = """
Promise.all(Array.from(document.querySelectorAll('a.serial')).map(async a => {
  const answer = await fetch(a.href);
  const page = new DOMParser().parseFromString(await answer.text(), 'text/html');
  return [a.getAttribute('href'), answer.status, page.querySelector('h1').textContent];
}))
"""


def _links_resolve(browser: Browser, url: str, expected: set[str]) -> None:
    assert browser.load(url).errors == []
    links = browser.evaluate_async(FETCH_SERIAL_LINKS)
    assert {href for href, _, _ in links} == {f"/units/{serial}" for serial in expected}
    for href, status, title in links:
        assert (status, title) == (200, f"Unit {href.removeprefix('/units/')}")


def test_serials_on_the_report_and_the_dashboard_link_to_their_unit_pages(
    browser: Browser, live_url: str, database: Database
) -> None:
    with database.session() as session:
        insert_line_history(session)
    _today(database)
    report = f"{live_url}/api/v1/reports/eol?format=html&from=2026-11-02&to=2026-11-03&list=all"
    _links_resolve(browser, report, {"U1", "U2", "U3", "U4", "U5", "U9"})
    today = {f"PT-{100 + i % 18:06d}" for i in range(24)}
    # the dashboard: today's latest 20 units, and the units on hold of any day
    browser.load(f"{live_url}/")
    held = browser.evaluate(
        "Array.from(document.querySelectorAll('table.held a.serial')).map(a => a.textContent)"
    )
    assert {"U3", "U5"} <= set(held)
    assert not {"U1", "U2", "U4", "U9"} & set(held)
    _links_resolve(browser, f"{live_url}/", today | set(held))


def test_a_unit_page_lists_every_run_and_a_failed_unit_gets_a_failure_report(
    browser: Browser, live_url: str, database: Database
) -> None:
    with database.session() as session:
        insert_line_history(session)
    assert browser.load(f"{live_url}/units/U3").errors == []
    assert browser.evaluate("document.querySelectorAll('table.runs tr.run').length") == 2
    records = browser.evaluate_async(
        "Promise.all(Array.from(document.querySelectorAll('a.record'))"
        ".map(a => fetch(a.href).then(r => r.json())))"
    )
    assert [(r["serial"], r["verdict"]) for r in records] == [("U3", "fail"), ("U3", "fail")]
    browser.screenshot(f"unit-{database.engine.dialect.name}")
    browser.evaluate("document.getElementById('certificate').click()")
    browser.wait_for("location.pathname === '/api/v1/units/U3/certificate'")
    browser.wait_for("document.readyState === 'complete'")
    assert browser.evaluate("document.querySelector('h1').textContent") == "Failure report"
    assert "Calibration certificate" not in browser.evaluate("document.body.innerText")
    assert browser.evaluate("document.querySelectorAll('table.earlier tr').length") == 1 + 1
    browser.screenshot(f"failure-report-{database.engine.dialect.name}")


@pytest.mark.timeout(180)
def test_the_dashboard_shows_a_run_submitted_through_the_api_without_a_reload(
    browser: Browser, live_url: str, database: Database, station_key: str
) -> None:
    _today(database)
    assert browser.load(f"{live_url}/").errors == []
    browser.wait_for("document.body.dataset.following === 'yes'")
    browser.evaluate("window.sameDocument = true")
    record = make_record(serial="PT-LIVE-1", verdict="fail", started_at=datetime.now(UTC))
    answer = httpx.post(
        f"{live_url}/api/v1/runs",
        json=record.model_dump(mode="json", exclude={"failures"})
        | {"failures": [{"code": "offset", "message": "offset x out of limits"}]},
        headers={"Authorization": f"Bearer {station_key}"},
        timeout=HUNG_SERVER_S,
    )
    assert answer.status_code == 201
    row = "Array.from(document.querySelectorAll('table.units a.serial')).map(a => a.textContent)"
    assert "PT-LIVE-1" in browser.wait_for(f"{row}.includes('PT-LIVE-1') && {row}")
    held = "Array.from(document.querySelectorAll('table.held a.serial')).map(a => a.textContent)"
    assert "PT-LIVE-1" in browser.evaluate(held)
    assert browser.evaluate("document.getElementById('units-tested').textContent") == "19"
    assert browser.evaluate("window.sameDocument") is True  # updated in place, not reloaded


# -- offline documentation ---------------------------------------------------------------


@pytest.mark.timeout(180)
def test_docs_and_redoc_render_with_every_other_host_unreachable(
    tmp_path: Path, live_url: str
) -> None:
    operations = sum(
        len(ops) for ops in local_get(f"{live_url}/openapi.json").json()["paths"].values()
    )
    with chromium(tmp_path / "chromium", flags=OFFLINE) as browser:
        assert browser.load(f"{live_url}/docs").errors == []
        shown = browser.wait_for(
            f"document.querySelectorAll('.opblock').length === {operations} && "
            "document.querySelectorAll('.opblock').length"
        )
        assert shown == operations
        own = (live_url, f"blob:{live_url}", "data:")  # the server's, or made in the page
        assert all(url.startswith(own) for url in browser.requested())
        unreachable = browser.evaluate_async(  # the CDN the docs would otherwise come from
            "fetch('https://cdn.jsdelivr.net/npm/swagger-ui-dist@5/swagger-ui.css')"
            ".then(() => 'reached', () => 'unreachable')"
        )
        assert unreachable == "unreachable"
        browser.screenshot("docs-offline")
        assert browser.load(f"{live_url}/redoc").errors == []
        browser.wait_for("document.querySelectorAll('[data-section-id^=\"operation/\"]').length")
        # the side menu's Redocly logo, drawn last, is the bundle's one CDN address
        browser.wait_for("document.querySelector('img[alt=\"redocly logo\"]') !== null")
        assert all(url.startswith(own) for url in browser.requested())
        assert not [url for url in browser.requested() if "redoc.ly" in url]
