"""Runs a station stored through its own database at the ends of the calendar (its clock
reset to the year 1, or set to the last moments of 9999) and on an ordinary day."""

from datetime import UTC, datetime, timedelta

from db import Database
from station.domain.quality.days import FIRST, LAST
from station.domain.record.records import RunRecord
from station.results.storage import DatabaseStore
from tests.db.records import RUN_SECONDS, make_record

#: Each unit's run start: two minutes into the year 1, 95 s (its length) before the last
#: moment (where it ends, failing), an ordinary morning.
UNITS = {
    "PT-000001": FIRST + timedelta(minutes=2),
    "PT-009999": LAST - timedelta(seconds=RUN_SECONDS),
    "PT-002026": datetime(2026, 11, 2, 8, tzinfo=UTC),
}
FAILING = "PT-009999"
#: The station's golden-unit check at the first moment: the year-1 unit's reference in
#: every zone and shift plan (its day and its shift begin at the first moment).
GOLDEN = "GOLD-0001"


def calendar_end_records() -> list[RunRecord]:
    """The golden check, then the units' runs."""
    golden = make_record(serial=GOLDEN, started_at=FIRST, purpose="golden")
    return [
        golden,
        *(
            make_record(
                serial=serial,
                started_at=start,
                verdict="fail" if serial == FAILING else "pass",
                **({"finished_at": LAST.isoformat()} if serial == FAILING else {}),
            )
            for serial, start in UNITS.items()
        ),
    ]


def store_calendar_ends(database: Database) -> list[RunRecord]:
    """Store the runs as a station does without a server, through its own database."""
    store = DatabaseStore(database=database)  # not closed: the test's database lives on
    records = calendar_end_records()
    for record in records:
        store.submit(record)
    return records
