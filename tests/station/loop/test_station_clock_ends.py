"""The station's own screen and golden-unit schedule over runs stamped at the ends of the
calendar (a clock reset to the year 1 or set to 9999), in the station's local zone at
either extreme: said in UTC where that zone cannot show them, never an OverflowError."""

import time
from collections.abc import Callable, Iterator
from datetime import UTC, datetime, timedelta

import pytest

from station.domain.quality.days import FIRST, LAST
from station.domain.quality.golden import GoldenUnit, due
from station.loop.unit_history import UnitHistory
from tests.db.records import RUN_SECONDS, make_record

RUN = timedelta(seconds=RUN_SECONDS)


@pytest.fixture
def station_zone(monkeypatch: pytest.MonkeyPatch) -> Iterator[Callable[[str], None]]:
    """Sets the station's local zone (``TZ``); the test process's own is back after."""

    def set_zone(zone: str) -> None:
        monkeypatch.setenv("TZ", zone)
        time.tzset()

    yield set_zone
    monkeypatch.undo()
    time.tzset()


@pytest.mark.parametrize(
    ("zone", "finished", "shown"),
    [
        ("Etc/GMT-14", LAST, "9999-12-31 23:59 UTC"),  # +14: past 9999 on its clock
        ("Etc/GMT-14", FIRST + RUN, "0001-01-01 14:01"),
        ("Etc/GMT+12", FIRST + RUN, "0001-01-01 00:01 UTC"),  # −12: before year 1
        ("Etc/GMT+12", LAST, "9999-12-31 11:59"),
    ],
)
def test_a_unit_that_passed_at_the_ends_of_the_calendar_is_said_at_its_scan(
    station_zone: Callable[[str], None], zone: str, finished: datetime, shown: str
) -> None:
    station_zone(zone)
    run = make_record(
        serial="PT000123", started_at=finished - RUN, finished_at=finished.isoformat()
    )
    decision = UnitHistory(run.serial, (run,)).at_scan(3)
    assert decision.text == f"PT000123 passed at {shown} on {run.station_id}: calibrate again? y/n"


@pytest.mark.parametrize("zone", ["Etc/GMT-14", "Etc/GMT+12"])
def test_the_golden_schedule_reads_a_check_stamped_at_the_ends(
    station_zone: Callable[[str], None], zone: str
) -> None:
    """A check stamped in the last hour of 9999 is the latest: within its period, and no
    shift has started since; one of the year 1 is long past its period."""
    station_zone(zone)
    unit = GoldenUnit(
        serial="GU-001",
        offset_counts=(2081.9, 2041.2, 1960.5),
        sensitivity_counts_per_g=(813.95, 815.66, 820.17),
        shift_starts=(datetime.min.time(),),
    )
    now = datetime(2026, 11, 2, 8, tzinfo=UTC)
    assert not due(unit, LAST - timedelta(hours=1), now)
    assert due(unit, FIRST, now)
