"""The report page's charts, axes and filter form in a real headless Chromium."""

from db import Database
from tests.browser import Browser
from tests.db.eol_data import RUNS, insert_line_history
from tests.servers import serving

#: Text of every chart that reaches past its own drawing area (cut labels).
CUT_LABELS = """
Array.from(document.querySelectorAll('svg.chart')).flatMap(svg => {
  const box = svg.getBoundingClientRect();
  return Array.from(svg.querySelectorAll('text')).filter(t => {
    const r = t.getBoundingClientRect();
    return r.width > 0 && (r.left < box.left - 0.5 || r.right > box.right + 0.5
                           || r.top < box.top - 0.5 || r.bottom > box.bottom + 0.5);
  }).map(t => t.textContent);
})
"""


def test_trend_and_control_charts_have_their_axes_and_no_label_is_cut(
    browser: Browser, live_url: str, database: Database
) -> None:
    with database.session() as session:
        insert_line_history(session)
    load = browser.load(f"{live_url}/api/v1/reports/eol?format=html")
    assert load.errors == []
    trend = "document.querySelectorAll('.trend svg.chart')"
    assert browser.evaluate(f"{trend}.length") >= 3
    # Every trend chart: a day tick with its date, and the value axis labelled.
    assert browser.evaluate(
        f"Array.from({trend}).every(s => s.querySelectorAll('g.tick').length >= 1"
        " && s.textContent.includes('11-02'))"
    )
    charts = browser.evaluate(
        "Array.from(document.querySelectorAll('svg.chart title'))"
        ".map(t => t.textContent).filter(t => t.startsWith('I-MR'))"
    )
    charted = len(RUNS)  # every run of the history has coefficients
    assert len(charts) == 6
    assert all(t.endswith(f"{charted} of {charted} runs plotted") for t in charts)
    # Time ticks under both panels, values on the centre and limit lines.
    first = (
        "Array.from(document.querySelectorAll('svg.chart'))"
        ".find(s => s.querySelector('title').textContent.startsWith('I-MR'))"
    )
    assert browser.evaluate(f"{first}.querySelectorAll('g.tick').length") >= 2 * 2
    labels = browser.evaluate(
        f"Array.from({first}.querySelectorAll('text')).map(t => t.textContent)"
    )
    assert any(label.startswith("UCL ") for label in labels)
    assert any(label.startswith("x̄ ") for label in labels)
    assert any(label.startswith("MR̄ ") for label in labels)
    assert browser.evaluate(CUT_LABELS) == []


def test_the_shift_trend_is_drawn_per_shift_where_the_plant_has_shifts(
    browser: Browser, database: Database, database_url: str
) -> None:
    with database.session() as session:
        insert_line_history(session)
    with serving(database_url, plant_shifts="06:00,14:00,22:00") as base:
        load = browser.load(f"{base}/api/v1/reports/eol?format=html")
    assert load.errors == []
    shifts = "document.querySelectorAll('.shift-trend svg.chart')"
    assert browser.evaluate(f"{shifts}.length") == 2  # units, and the yields
    # The history's runs (08:00–13:00 UTC on 11-02) are in its 06:00 shift.
    assert browser.evaluate(
        f"Array.from({shifts}).every(s => s.querySelectorAll('g.tick').length >= 1"
        " && s.textContent.includes('11-02 06:00'))"
    )
    heading = browser.evaluate(
        "Array.from(document.querySelectorAll('h2')).map(h => h.textContent)"
        ".find(t => t.startsWith('Trend per shift'))"
    )
    assert heading == "Trend per shift (UTC)"
    assert browser.evaluate(CUT_LABELS) == []


def test_the_filter_form_narrows_the_report(
    browser: Browser, live_url: str, database: Database
) -> None:
    with database.session() as session:
        insert_line_history(session)
    assert browser.load(f"{live_url}/api/v1/reports/eol?format=html").errors == []
    browser.follow(
        "const form = document.querySelector('form.filters');"
        "form.elements['station'].value = 'st2';"
        "form.elements['from'].value = '2026-11-02';"
        "form.elements['to'].value = '2026-11-03';"
        "form.elements['list'].value = 'all';"
        "form.requestSubmit(); 1"
    )
    url = browser.evaluate("location.href")
    assert "station=st2" in url
    assert "from=2026-11-02" in url
    assert "· station st2" in browser.evaluate("document.querySelector('.meta').textContent")
    st2 = {run[1] for run in RUNS if run[2] == "st2"}
    rows = browser.evaluate("document.querySelectorAll('table.units tr').length")
    assert rows == 1 + len(st2)
    # The form shows the filter it was answered with; the empty fields stay empty.
    assert (
        browser.evaluate("document.querySelector('form.filters').elements['station'].value")
        == "st2"
    )
    assert browser.evaluate("document.querySelector('form.filters').elements['lot'].value") == ""
    browser.screenshot(f"eol-report-filtered-{database.engine.dialect.name}")
