"""``calstation report`` over runs a station stored through its own database at the ends
of the calendar (the years 1 and 9999): every format, in any plant zone and shift plan,
on both backends, without a traceback from day + 1, plant_date or the shifts."""

import json
import os

import pytest

from db import Database
from station.domain.constants import FORMATS
from tests.calendar_ends import UNITS, store_calendar_ends
from tests.conftest import CliRunner

#: The extremes of the offsets (+14 since 1994, +14 always, −12) and two DST zones.
ZONES = [
    "UTC",
    "Pacific/Kiritimati",
    "Etc/GMT-14",
    "Etc/GMT+12",
    "Europe/Berlin",
    "America/New_York",
]
#: None, three shifts (the last across midnight), two with a night shift from 22:00.
SHIFT_PLANS = ["", "06:00,14:00,22:00", "22:00,06:00"]


@pytest.fixture
def calendar_ends(database: Database) -> None:
    store_calendar_ends(database)


def _report(call_cli: CliRunner, database_url: str, *arguments: str) -> str:
    env = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    result = call_cli("report", *arguments, "--database-url", database_url, env=env)
    assert result.returncode == 0, (arguments, result.stderr)
    assert result.stderr == ""
    return result.stdout


@pytest.mark.usefixtures("calendar_ends")
@pytest.mark.parametrize("zone", ZONES)
def test_every_format_reports_the_years_1_and_9999_in_any_zone_and_shift_plan(
    call_cli: CliRunner, database_url: str, zone: str
) -> None:
    for shifts in SHIFT_PLANS:
        plant = ("--timezone", zone, "--shifts", shifts)
        for format in FORMATS:
            shown = _report(call_cli, database_url, *plant, "--format", format)
            assert all(serial in shown for serial in UNITS), (shifts, format)
        report = json.loads(_report(call_cli, database_url, *plant, "--format", "json"))
        assert report["summary"]["units_tested"] == len(UNITS)
        # The trend's latest days end on the last date, holding the unit of 9999 (in
        # every zone: a wall clock past 9999 keeps the last date).
        assert report["trend"][-1]["day"] == "9999-12-31"
        assert [day["units"] for day in report["trend"]][-1:] == [1]
        assert sum(day["units"] for day in report["trend"]) == 1
        if shifts:
            assert sum(shift["units"] for shift in report["shift_trend"]) == 1
            assert report["shift_trend"][-1]["end"] == "9999-12-31T23:59:59.999999Z"
        # From the first moment to the third day: the year-1 unit on the first date.
        early = ("--from", "0001-01-01", "--to", "0001-01-03", "--format", "json")
        report = json.loads(_report(call_cli, database_url, *plant, *early))
        assert report["summary"]["units_tested"] == 1
        assert report["trend"][0]["day"] == "0001-01-01"
        assert sum(day["units"] for day in report["trend"]) == 1
        if shifts:
            assert report["shift_trend"][0]["start"] == "0001-01-01T00:00:00Z"
            assert sum(shift["units"] for shift in report["shift_trend"]) == 1
