"""Click-through from the report's charts in a real headless Chromium: a control chart's
point opens its run's unit page, a point of the yield per day or per shift opens the
report of that period with every unit listed (the units that point counts)."""

from datetime import timedelta
from typing import Any

import httpx
import pytest

from db import Database, RunRepository
from tests.browser import Browser
from tests.db.records import T0, make_record
from tests.servers import HUNG_SERVER_S, local_get, serving

#: Units per day at the station the report is narrowed to, over three days.
PER_DAY, DAYS = 3, 3

#: A click at the centre of the ``nth`` point from the left of the first chart of
#: ``block`` (its circles of class ``kind``, or in a group of that class): the page's own
#: click handler sees a click where a reader would click.
CLICK = """
(() => {{
  const chart = document.querySelector("{block} svg");
  const circles = Array.from(chart.querySelectorAll("circle.{kind}, g.{kind} circle"))
    .sort((a, b) => a.cx.baseVal.value - b.cx.baseVal.value);
  const box = circles[{nth}].getBoundingClientRect();
  circles[{nth}].dispatchEvent(new MouseEvent("click", {{
    bubbles: true, clientX: box.left + box.width / 2, clientY: box.top + box.height / 2 }}));
  return circles.length;
}})()
"""


def _history(database: Database) -> None:
    """Three units a day at st1 (the first of each day failing) and one at st2, over three
    days from 08:00 UTC; offsets that differ from run to run."""
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        for day in range(DAYS):
            start = T0 + timedelta(days=day)
            for k in range(PER_DAY):
                repository.submit(
                    make_record(
                        serial=f"PT{day}{k:05d}",
                        station_id="st1",
                        started_at=start + timedelta(minutes=10 * k),
                        offset=(2040.0 + 3 * day + k, 2048.0, 1960.5),
                        verdict="fail" if k == 0 else "pass",
                    )
                )
            repository.submit(
                make_record(serial=f"PT{day}99999", station_id="st2", started_at=start)
            )


def test_a_control_chart_point_opens_its_unit(
    browser: Browser, database: Database, database_url: str
) -> None:
    _history(database)
    with serving(database_url) as base:
        report: dict[str, Any] = local_get(
            f"{base}/api/v1/reports/eol", params={"station": "st1"}, timeout=HUNG_SERVER_S
        ).json()
        points = report["control_charts"][0]["points"]
        assert len(points) == PER_DAY * DAYS
        for nth in (0, 4, len(points) - 1):
            assert browser.load(f"{base}/api/v1/reports/eol?format=html&station=st1").errors == []
            browser.follow(CLICK.format(block=".control-charts", kind="point", nth=nth))
            serial = points[nth]["serial"]
            assert browser.evaluate("location.pathname") == f"/units/{serial}"
            assert serial in browser.evaluate("document.querySelector('h1').textContent")


def _listed(browser: Browser) -> list[str]:
    """The serials of the report page's unit list."""
    found: list[str] = browser.evaluate(
        "Array.from(document.querySelectorAll('table.units a.serial')).map(a => a.textContent)"
    )
    return found


@pytest.mark.parametrize(("block", "shifts"), [(".trend", ""), (".shift-trend", "06:00,18:00")])
def test_a_yield_point_of_a_day_or_shift_opens_its_units(
    browser: Browser, database: Database, database_url: str, block: str, shifts: str
) -> None:
    _history(database)
    settings = {"plant_shifts": shifts} if shifts else {}
    with serving(database_url, **settings) as base:
        assert browser.load(f"{base}/api/v1/reports/eol?format=html&station=st1").errors == []
        # The yield chart of the block first: its first-pass and final yield points, one
        # per period each; from the left, the third and fourth are the middle day's (or
        # its 06:00 shift's).
        browser.evaluate(
            f"const y = Array.from(document.querySelectorAll('{block} svg'))"
            ".find(s => s.querySelector('title').textContent.startsWith('yield per'));"
            f"document.querySelector('{block}').prepend(y); 1"
        )
        first_pass = browser.evaluate(
            f"document.querySelectorAll('{block} svg')[0].querySelectorAll('.trend-points')[0]"
            ".querySelectorAll('circle').length"
        )
        assert first_pass == DAYS
        browser.follow(CLICK.format(block=block, kind="trend-points", nth=2))
        url = httpx.URL(browser.evaluate("location.href"))
        day = (T0 + timedelta(days=1)).date()
        assert url.params["list"] == "all"
        assert url.params["station"] == "st1"
        if shifts:  # the 06:00 shift of the middle day, to the next shift at 18:00
            assert (url.params["from"], url.params["to"]) == (f"{day}T06:00", f"{day}T18:00")
        else:
            assert (url.params["from"], url.params["to"]) == (str(day), str(day.replace(day=4)))
        assert sorted(_listed(browser)) == [f"PT1{k:05d}" for k in range(PER_DAY)]
