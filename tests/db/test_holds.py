"""The units on hold the dashboard lists: latest run failed (aborts aside), newest first,
and their count from the roll-ups, against the same units worked out by hand."""

from datetime import timedelta

from sqlalchemy.orm import Session

from db import RunRepository
from db.report.holds import held_units
from db.report.reports import eol_report
from station.domain.quality.figures import ReportFilter
from station.domain.record.records import HoldReview
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


def test_the_report_counts_open_holds_by_age_and_cause_until_a_review_closes_one(
    session: Session,
) -> None:
    repository = RunRepository(session)
    noise = {"verdict": "fail", "failures": [{"code": "pose_noise", "message": "noise"}]}
    for hours, serial, outcome in [*RUNS, (40, "G", noise), (200, "H", noise)]:
        repository.submit(
            make_record(serial=serial, started_at=T0 + timedelta(hours=hours), **outcome)
        )
    session.flush()
    # Held: B (1 h), E (7 h), F (30 h), G (40 h), H (200 h), by their latest runs' starts.
    now = T0 + timedelta(hours=210)
    holds = eol_report(session, ReportFilter(), now=now).open_holds
    assert holds is not None
    ages = {count.label: count.units for count in holds.by_age}
    # H is 10 h old; F and G 170–180 h (over 7 days); B and E 203–209 h.
    assert ages == {"< 1 day": 1, "1–7 days": 0, "> 7 days": 4}
    assert [(c.label, c.units) for c in holds.by_cause] == [("offset", 3), ("pose_noise", 2)]
    assert holds.total == 5
    later = eol_report(session, ReportFilter(), now=T0 + timedelta(hours=60)).open_holds
    assert later is not None
    # At 60 h: H is in the future of the report's time (young); G 20 h; the rest over a day.
    assert {c.label: c.units for c in later.by_age} == {"< 1 day": 2, "1–7 days": 3, "> 7 days": 0}
    latest_e = repository.latest_for_serial("E")
    assert latest_e is not None
    repository.add_review(
        HoldReview(
            serial="E",
            run_id=latest_e.run_id,
            reviewed_at=now,
            reviewer="qe-ana",
            root_cause="loose jig",
            repair_action="jig tightened",
            decision="retest",
        )
    )
    session.flush()
    closed = eol_report(session, ReportFilter(), now=now).open_holds
    assert closed is not None
    assert closed.total == 4
    assert [(c.label, c.units) for c in closed.by_cause] == [("offset", 2), ("pose_noise", 2)]
    # A station's report counts its own units only.
    none = eol_report(session, ReportFilter(station_id="elsewhere"), now=now).open_holds
    assert none is not None
    assert (none.total, none.by_cause) == (0, [])
