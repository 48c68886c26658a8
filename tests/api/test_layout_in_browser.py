"""The pages keep to the window, in headless Chromium: a unit page at 1,400 px, the
dashboard at 420 px; a table wider than its box scrolls in it, a chart scales down to
the window (tests/api/test_widths_in_browser.py checks every page in every language)."""

from datetime import UTC, datetime, timedelta

from db import Database, RunRepository
from tests.browser import WIDTH, Browser
from tests.db.records import make_record

#: How far the page reaches past the window's right edge (px; 0 when it fits).
OVERFLOW = "document.documentElement.scrollWidth - window.innerWidth"
#: Charts reaching past the window's right edge.
PAST_THE_WINDOW = (
    "Array.from(document.querySelectorAll('svg.chart'))"
    ".filter(s => s.getBoundingClientRect().right > window.innerWidth + 1).length"
)
#: Tables wider than their box that do not scroll in it.
UNSCROLLED = (
    "Array.from(document.querySelectorAll('table')).filter(t => {"
    " const box = t.parentElement;"
    " return t.scrollWidth > box.clientWidth + 1 &&"
    " getComputedStyle(box).overflowX !== 'auto'; }).length"
)

LONG_REASON = {
    "code": "pose_noise",
    "message": "pose noise x (pose 3) 8.59057 counts, the unit moved while the pose was captured",
    "measured": 8.59057,
    "upper": 8.0,
}


def _store_today(database: Database) -> None:
    now = datetime.now(UTC).replace(microsecond=0)
    start = max(now - timedelta(minutes=30), now.replace(hour=0, minute=0, second=0))
    with database.session() as session:
        repository = RunRepository(session)
        for i in range(12):
            repository.submit(
                make_record(
                    serial="PT-WIDE-001" if i < 6 else f"PT-{i:06d}",
                    station_id=f"line1-station-{1 + i % 2}",
                    operator_id="operator-with-a-long-name",
                    verdict="fail" if i % 3 == 0 else "pass",
                    failures=[LONG_REASON, LONG_REASON] if i % 3 == 0 else [],
                    lot="LOT-2026-11-A",
                    started_at=start + timedelta(minutes=2 * i),
                )
            )
        session.commit()


def test_a_unit_page_fits_a_1400_px_window(
    browser: Browser, live_url: str, database: Database
) -> None:
    _store_today(database)
    assert browser.evaluate("window.innerWidth") == WIDTH
    certificate = "/api/v1/units/PT-WIDE-001/certificate"
    for page in (
        "/units/PT-WIDE-001",
        certificate,
        f"{certificate}?lang=ko",
        f"{certificate}?lang=zh",
    ):
        assert browser.load(f"{live_url}{page}").errors == []
        assert browser.evaluate(OVERFLOW) <= 0, page
        assert browser.evaluate(UNSCROLLED) == 0, page


def test_the_dashboard_keeps_to_a_420_px_window(
    browser: Browser, live_url: str, database: Database
) -> None:
    _store_today(database)
    browser.call(
        "Emulation.setDeviceMetricsOverride",
        width=420,
        height=900,
        deviceScaleFactor=1,
        mobile=False,
    )
    for page in ("/", "/api/v1/reports/eol?format=html&list=all"):
        assert browser.load(f"{live_url}{page}").errors == []
        assert browser.evaluate("window.innerWidth") == 420
        assert browser.evaluate(OVERFLOW) <= 0, page
        assert browser.evaluate(UNSCROLLED) == 0, page
        assert browser.evaluate("document.querySelectorAll('svg.chart').length") > 0
        assert browser.evaluate(PAST_THE_WINDOW) == 0, page  # scaled to the window
