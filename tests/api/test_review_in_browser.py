"""A held unit reviewed from its page in a real headless Chromium: the form typed in and
submitted, the page back with the review listed; a wrong key answers a page in one line."""

from datetime import timedelta

import pytest

from db import Database, RunRepository
from tests.browser import Browser
from tests.db.records import T0, make_record

FAILED = {"verdict": "fail", "failures": [{"code": "offset", "message": "offset x high"}]}


def _fill(browser: Browser, key: str) -> None:
    browser.evaluate(
        "(() => { const f = document.querySelector('form.review');"
        " f.root_cause.value = 'loose jig clamp'; f.repair_action.value = 'clamp replaced';"
        f" f.decision.value = 'retest'; f.key.value = {key!r};"
        " f.querySelector('button[type=submit]').click(); })()"
    )


@pytest.mark.timeout(120)
def test_a_held_unit_is_reviewed_through_its_pages_form(
    browser: Browser, live_url: str, database: Database, quality_key: str
) -> None:
    with database.session() as session, session.begin():
        for i in range(2):
            RunRepository(session).submit(
                make_record(serial="PT000510", started_at=T0 + timedelta(hours=i), **FAILED)
            )
    assert browser.load(f"{live_url}/units/PT000510").errors == []
    assert browser.evaluate("document.querySelectorAll('tr.review').length") == 0
    _fill(browser, "not-a-key")
    browser.wait_for("location.pathname === '/units/PT000510/reviews'")
    browser.wait_for("document.readyState === 'complete'")
    problem = browser.evaluate("document.getElementById('problem').textContent")
    assert "unknown or revoked API key" in problem
    assert browser.load(f"{live_url}/units/PT000510").errors == []
    _fill(browser, quality_key)
    browser.wait_for("location.hash === '#reviews'")
    browser.wait_for("document.querySelectorAll('tr.review').length === 1")
    row = browser.evaluate("document.querySelector('tr.review').innerText")
    for shown in ("qe-ana", "loose jig clamp", "retest"):
        assert shown in row
    browser.screenshot(f"unit-reviewed-{database.engine.dialect.name}")
