"""Every page over runs a station stored through its own database at the ends of the
calendar (the years 1 and 9999) and on an ordinary day, on a real server in the plant
zones at the extremes and with shift plans (none of them a 500 from day + 1,
plant_date or the shifts): the report in each format, its trend links to the first and last days and
shifts, the split, dashboard, alerts, station, unit and certificate pages. A submitted
moment beyond the calendar is a 422 naming its field."""

import html
import re
from collections.abc import Iterator

import httpx
import pytest

from db import Database
from tests.calendar_ends import FAILING, GOLDEN, UNITS, store_calendar_ends
from tests.db.records import make_record
from tests.servers import STATION, local_client, serving

EOL = "/api/v1/reports/eol"
#: Plants: UTC without shifts; +14 with three shifts; −12 with a night shift from 22:00;
#: a daylight-saving zone with three shifts.
PLANTS = [
    ("UTC", ""),
    ("Pacific/Kiritimati", "06:00,14:00,22:00"),
    ("Etc/GMT+12", "22:00,06:00"),
    ("America/New_York", "06:00,14:00,22:00"),
]
#: A trend chart's periods (``html.trend_runs``): their bounds, a common prefix and the
#: address with ``{0}`` (a period's start) and ``{1}`` (its end).
PERIOD_LINKS = re.compile(
    r'data-runs="([^"]*)" data-prefix="([^"]*)" data-x="[^"]*" data-href="([^"]*\{1\}[^"]*)"'
)


@pytest.fixture(params=PLANTS, ids=[zone for zone, _ in PLANTS])
def plant(
    request: pytest.FixtureRequest, database: Database, database_url: str
) -> Iterator[httpx.Client]:
    """A server of the plant over the stored runs, and a client of it."""
    store_calendar_ends(database)
    zone, shifts = request.param
    with (
        serving(database_url, plant_timezone=zone, plant_shifts=shifts) as base,
        local_client(base) as client,
    ):
        yield client


def _ok(client: httpx.Client, url: str, **params: str) -> str:
    answer = client.get(url, params=params)
    assert answer.status_code == 200, (url, params, answer.text[:500])
    return answer.text


def _period_pages(client: httpx.Client, page: str) -> list[str]:
    """The reports the first and the last period of each trend chart of ``page`` open."""
    charts = PERIOD_LINKS.findall(page)
    assert charts, "no trend chart"
    opened = []
    for runs, prefix, href in charts:
        bounds = [prefix + token for token in runs.split()]
        for start, end in (bounds[:2], bounds[-2:]):
            address = html.unescape(href).replace("{0}", start).replace("{1}", end)
            opened.append(_ok(client, address if address.startswith("/") else EOL + address))
    return opened


def test_every_page_answers_over_the_years_1_and_9999(plant: httpx.Client) -> None:
    client = plant
    report = _ok(client, EOL, format="html", list="all")
    assert all(serial in report for serial in UNITS)
    # The last day's and the last shift's reports list the unit of 9999.
    assert all(FAILING in page for page in _period_pages(client, report)[1::2])
    early = _ok(
        client, EOL, format="html", list="all", **{"from": "0001-01-01", "to": "0001-01-03"}
    )
    assert "PT-000001" in early
    assert all("PT-000001" in page for page in _period_pages(client, early)[::2])
    for format in ("json", "csv"):
        assert all(serial in _ok(client, EOL, format=format) for serial in UNITS)
    assert all(serial in _ok(client, EOL + "/runs.csv") for serial in UNITS)
    code = client.get(EOL, params={"format": "json"}).json()["pareto"][0]["code"]
    assert FAILING in _ok(client, EOL + "/failures", code=code)
    for format in ("html", "json"):
        _ok(client, "/api/v1/reports/split", by="station", parameter="offset_x", format=format)
    _ok(client, "/")
    _ok(client, "/alerts")
    assert GOLDEN in _ok(client, f"/stations/{STATION}")
    for serial in [*UNITS, GOLDEN]:
        assert serial in _ok(client, f"/units/{serial}")
    for serial in UNITS:
        assert serial in _ok(client, f"/api/v1/units/{serial}/certificate")
    # The year-1 unit's reference: the golden check at the first moment, the start of
    # its day and of its shift in every zone.
    assert GOLDEN in _ok(client, "/api/v1/units/PT-000001/certificate")


@pytest.mark.parametrize(
    ("field", "moment"),
    [
        ("started_at", "0001-01-01T00:30:00+01:00"),  # before the year 1 in UTC
        ("finished_at", "9999-12-31T23:30:00-01:00"),  # past 9999 in UTC
    ],
)
def test_a_submitted_moment_beyond_the_calendar_is_422_naming_its_field(
    client: httpx.Client, station_key: str, field: str, moment: str
) -> None:
    body = make_record().model_dump(mode="json")
    body[field] = moment
    answer = client.post(
        "/api/v1/runs", json=body, headers={"Authorization": f"Bearer {station_key}"}
    )
    assert answer.status_code == 422, answer.text
    [error] = answer.json()["errors"]
    assert error["loc"] == f"body.{field}"
    assert "is outside the years 1…9999 in UTC" in error["msg"]
