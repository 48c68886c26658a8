"""The units on hold the dashboard lists: latest run failed (aborts aside), newest first,
and their count from the roll-ups, against the same units worked out by hand."""

from datetime import timedelta

from sqlalchemy.orm import Session

from db import RunRepository
from db.holds import held_units
from tests.db.records import T0, make_record
from tests.db.test_unit_truth import ABORT

FAIL = {"verdict": "fail", "failures": [{"code": "offset", "message": "offset x high"}]}

#: (hours after T0, serial, how the run ended): B, E and F end on hold; D passed and
#: was aborted at a rescan, so it still ships.
RUNS = [
    (0, "A", {}),
    (1, "B", FAIL),
    (2, "C", FAIL),
    (3, "C", {}),
    (4, "D", {}),
    (5, "D", ABORT),
    (6, "E", FAIL),
    (7, "E", FAIL),
    (30, "F", FAIL),  # the next day
]


def test_the_latest_units_on_hold_and_how_many(session: Session) -> None:
    repository = RunRepository(session)
    for hours, serial, outcome in RUNS:
        repository.submit(
            make_record(serial=serial, started_at=T0 + timedelta(hours=hours), **outcome)
        )
    session.flush()
    held = held_units(session, limit=2)
    assert held.total == 3
    assert [unit.serial for unit in held.units] == ["F", "E"]
    assert held.units[1].attempts == 2
    assert held.units[1].holds is not None
    assert held.units[1].holds.verdict == "fail"
    assert [unit.serial for unit in held_units(session, limit=50).units] == ["F", "E", "B"]
