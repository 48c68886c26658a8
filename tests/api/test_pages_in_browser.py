"""The report page, the dashboard and a certificate in a real headless Chromium.

Each page is served by the live server, loaded by Chromium, checked for its charts and
for console errors, and saved as a screenshot under ``artifacts/``.
"""

from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

from db import Database, RunRepository
from tests.browser import Browser, chromium, chromium_binary
from tests.db.eol_data import insert_line_history
from tests.db.records import make_record

COUNT_CHARTS = "document.querySelectorAll('svg.chart').length"
DRAWN_CHARTS = (
    "Array.from(document.querySelectorAll('svg.chart'))"
    ".filter(s => s.getBoundingClientRect().width > 100).length"
)


@pytest.fixture
def browser(tmp_path: Path) -> Iterator[Browser]:
    chromium_binary()
    with chromium(tmp_path / "chromium") as browser:
        yield browser


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
    assert browser.evaluate("document.querySelectorAll('rect.bar').length") >= 3 + 13
    # the held units: U3 and U5
    assert browser.evaluate("document.querySelectorAll('table.units tr').length") == 1 + 2


def test_dashboard_renders_today_and_reloads_itself(
    browser: Browser, live_url: str, database: Database
) -> None:
    _today(database)
    _check(browser, f"{live_url}/", f"dashboard-{database.engine.dialect.name}", charts=7)
    assert browser.evaluate("document.getElementById('units-tested').textContent") == "18"
    assert browser.evaluate("document.querySelectorAll('circle.point').length") == 6 * 24
    refresh = browser.evaluate(
        "document.querySelector('meta[http-equiv=refresh]').getAttribute('content')"
    )
    assert refresh == "30"


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
