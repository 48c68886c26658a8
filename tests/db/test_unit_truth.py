"""An attempt that wrote nothing into a unit never changes what the unit is known to hold.

A unit that passed, scanned again and aborted (or failed before its coefficients were
written) still holds its verified coefficients: its answer says so beside the latest
attempt, and the end-of-line report still counts it passed and ships it.
"""

from datetime import timedelta
from typing import Any

from sqlalchemy import select, update
from sqlalchemy.orm import Session

from db import RunRepository
from db.database import rewrite_if_stale
from db.models import Unit
from db.report.reports import eol_report
from db.store.units import answers_are_stale
from station.domain.quality.figures import ReportFilter
from station.domain.record.records import RunRecord
from station.domain.record.unit_state import UnitCalibration
from tests.db.records import T0, make_record

ABORT: dict[str, Any] = {
    "verdict": "fail",
    "failures": [{"code": "aborted", "message": "aborted by the operator"}],
    "coefficients": None,
    "quality": None,
}


def _answer(session: Session, serial: str) -> UnitCalibration:
    stored = session.scalars(select(Unit.calibration).where(Unit.serial == serial)).one()
    return UnitCalibration.model_validate_json(stored)


def _pass_then(session: Session, **later: Any) -> tuple[RunRecord, RunRecord]:
    repo = RunRepository(session)
    passed = make_record(disposition="ship")
    again = make_record(started_at=T0 + timedelta(hours=2), **later)
    repo.submit(passed)
    repo.submit(again)
    session.flush()
    return passed, again


def test_an_aborted_rescan_leaves_the_held_coefficients_and_the_verdict(session: Session) -> None:
    passed, aborted = _pass_then(session, disposition="ship", **ABORT)
    unit = _answer(session, passed.serial)
    assert unit.verdict == "pass"
    assert unit.attempts == 1
    assert unit.holds is not None
    assert passed.coefficients is not None
    assert (unit.holds.run_id, unit.holds.offset) == (passed.run_id, passed.coefficients.offset)
    assert unit.latest.run_id == aborted.run_id
    assert (unit.latest.verdict, unit.latest.wrote_unit) == ("fail", False)
    assert unit.latest.disposition == "ship"
    assert [f.code for f in unit.latest.failures] == ["aborted"]


def test_the_report_counts_a_passed_unit_whose_rescan_was_aborted_as_passed(
    session: Session,
) -> None:
    passed, _ = _pass_then(session, **ABORT)
    report = eol_report(session, ReportFilter())
    s = report.summary
    # the abort is no attempt: no retest, no failure in the Pareto, counted apart
    assert (s.runs, s.runs_passed, s.retests, s.aborted_runs) == (2, 1, 0, 1)
    assert (s.units_tested, s.units_passed, s.units_failed, s.final_yield) == (1, 1, 0, 1.0)
    assert [(u.serial, u.disposition, u.runs) for u in report.units] == [(passed.serial, "ship", 2)]
    assert report.pareto == []


def test_a_failure_before_the_write_back_fails_the_unit_but_keeps_what_it_holds(
    session: Session,
) -> None:
    saturated = [{"code": "saturated", "message": "accelerometer y stuck at the ADC rail"}]
    passed, failed = _pass_then(session, verdict="fail", failures=saturated)
    unit = _answer(session, passed.serial)
    assert (unit.verdict, unit.attempts) == ("fail", 2)
    assert unit.holds is not None
    assert unit.holds.run_id == passed.run_id  # its coefficients never reached the unit
    assert (unit.latest.run_id, unit.latest.wrote_unit) == (failed.run_id, False)
    assert eol_report(session, ReportFilter()).summary.units_failed == 1


def test_a_failure_after_the_write_back_is_what_the_unit_holds(session: Session) -> None:
    output = [{"code": "unit_output", "message": "unit output 40 mg outside ≤ 30"}]
    passed, failed = _pass_then(session, verdict="fail", failures=output, offset=(2050, 2040, 2030))
    unit = _answer(session, passed.serial)
    assert unit.holds is not None
    assert (unit.holds.run_id, unit.holds.verdict) == (failed.run_id, "fail")
    assert unit.holds.offset.as_tuple() == (2050, 2040, 2030)


def test_answers_of_the_older_shape_are_rewritten_at_upgrade(session: Session) -> None:
    passed, _ = _pass_then(session, **ABORT)
    old = f'{{"serial":"{passed.serial}","verdict":"fail","offset":null}}'
    session.execute(update(Unit).values(calibration=old))
    assert answers_are_stale(session)
    assert rewrite_if_stale(session.connection())
    assert not answers_are_stale(session)
    assert _answer(session, passed.serial).verdict == "pass"
    assert not rewrite_if_stale(session.connection())


def test_every_run_keeps_where_the_unit_went(session: Session) -> None:
    repo = RunRepository(session)
    first = make_record(disposition="retest", **ABORT)
    second = make_record(started_at=T0 + timedelta(hours=1), disposition="ship")
    legacy = make_record(started_at=T0 + timedelta(hours=2))  # a station before dispositions
    for record in (first, second, legacy):
        repo.submit(record)
    session.flush()
    assert [run.disposition for run in repo.history(first.serial)] == ["retest", "ship", None]
    stored = repo.get(second.run_id)
    assert stored is not None
    assert stored.disposition == "ship"
    # The answer's latest attempt is the one without a disposition: it says none.
    assert _answer(session, first.serial).latest.disposition is None
