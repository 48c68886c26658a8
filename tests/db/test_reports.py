"""The end-of-line report's numbers on runs each test stores itself, on SQLite and
PostgreSQL (those on the shared line history: :mod:`tests.db.test_reports_line_history`)."""

from datetime import time, timedelta

import pytest
from sqlalchemy.orm import Session

from db import RunQuery, RunRepository
from db.report.reports import eol_report
from station.domain.product.limits import load_profile
from station.domain.quality.figures import ReportFilter
from station.report.render import render, rows
from tests.db.eol_data import SINCE, UNTIL
from tests.db.records import POSES_PER_RUN, T0, make_record


def test_an_empty_range_reports_zeros_and_no_ratios(session: Session) -> None:
    report = eol_report(session, ReportFilter(since=SINCE, until=SINCE))
    s = report.summary
    assert (s.runs, s.units_tested, s.poses) == (0, 0, 0)
    assert (s.report_yield, s.first_pass_yield, s.units_per_hour) == (None, None, None)
    assert report.pareto == report.units == report.control_charts == []
    assert all(p.count == 0 and p.mean is None for p in report.parameters)


def test_a_unit_counts_and_is_listed_where_its_first_run_is_with_its_latest_run(
    session: Session,
) -> None:
    repository = RunRepository(session)
    day = timedelta(days=1)
    # U1 fails on day 1 and passes its retest on day 2, a run that arrives first.
    repository.submit(make_record(serial="U1", started_at=T0 + day))
    repository.submit(make_record(serial="U1", verdict="fail", started_at=T0))
    session.commit()
    first = eol_report(session, ReportFilter(since=SINCE, until=SINCE + day))
    s = first.summary
    assert (s.runs, s.units_tested, s.first_pass_units, s.units_passed, s.retests) == (
        1,
        1,
        0,
        1,
        0,
    )
    # listed with the unit's latest run, the day after the range
    assert [(u.serial, u.disposition, u.runs) for u in first.units] == [("U1", "ship", 2)]
    assert (first.units[0].last_started_at, first.units_total) == (T0 + day, 1)
    second = eol_report(session, ReportFilter(since=SINCE + day, until=SINCE + 2 * day))
    s = second.summary
    assert (s.runs, s.units_tested, s.retests) == (1, 0, 1)
    assert (second.units, second.units_total) == ([], 0)


def test_filters_by_lot(session: Session) -> None:
    repository = RunRepository(session)
    for minute, lot in enumerate(["L1", "L2", None, "L1"]):
        repository.submit(
            make_record(
                serial=f"U{minute}", lot=lot, started_at=T0 + timedelta(minutes=10 * minute)
            )
        )
    session.commit()
    l1 = eol_report(session, ReportFilter(since=SINCE, until=UNTIL, lot="L1"))
    assert (l1.summary.runs, l1.units_total) == (2, 2)
    assert {u.serial for u in l1.units} == {"U0", "U3"}
    assert l1.filter.lot == "L1"
    listed = repository.list_runs(RunQuery(lot="L2"))
    assert [(r.serial, r.lot) for r in listed.runs] == [("U1", "L2")]


def test_a_station_filtered_page_agrees_with_itself(session: Session) -> None:
    """The issue's contradiction: a unit first tested at st2 and retested at st1 made the
    st1 row count it as st1's unit, first-pass, with no retest, while the "all" row of
    the same st1 page counted it nowhere and its run as a retest."""
    repository = RunRepository(session)
    plan = [("U1", "st2", "fail", 0), ("U1", "st1", "pass", 10), ("U2", "st1", "fail", 20)]
    for serial, station, verdict, minute in plan:
        repository.submit(
            make_record(
                serial=serial,
                station_id=station,
                verdict=verdict,
                started_at=T0 + timedelta(minutes=minute),
            )
        )
    session.commit()
    page = eol_report(session, ReportFilter(station_id="st1"))
    (row,) = page.stations
    assert row.station_id == "st1"
    assert row.summary == page.summary
    # st1's own units: those whose first run on the line was there (U2 only), and its runs.
    s = page.summary
    assert (s.units_tested, s.runs, s.retests, s.first_pass_units) == (1, 2, 1, 0)
    assert s.report_yield == pytest.approx(1 / 2)
    everything = eol_report(session, ReportFilter())
    rows = {r.station_id: r.summary for r in everything.stations}
    assert rows["st2"].units_tested == 1
    assert rows["st2"].final_yield == pytest.approx(1.0)  # U1's latest run passed (at st1)
    assert sum(r.units_tested for r in rows.values()) == everything.summary.units_tested == 2
    assert sum(r.retests for r in rows.values()) == everything.summary.retests == 1


@pytest.mark.parametrize("zone", ["UTC", "Europe/Berlin"])
def test_the_trends_pose_noise_capability_is_that_of_every_pose(
    session: Session, zone: str
) -> None:
    """The trend reads the pose noise from each run's sums over its poses; over a range
    of one day and one shift it equals the capability of every pose's value."""
    repository = RunRepository(session)
    for k in range(5):
        record = make_record(serial=f"N{k}", started_at=T0 + timedelta(minutes=10 * k))
        poses = [
            pose.model_copy(
                update={"std": pose.std.model_copy(update={"x": 0.7 + 0.37 * k + 0.11 * i})}
            )
            for i, pose in enumerate(record.poses)
        ]
        repository.submit(record.model_copy(update={"poses": tuple(poses)}))
    session.commit()
    report = eol_report(
        session,
        ReportFilter(since=T0, until=T0 + timedelta(hours=1)),
        zone=zone,
        shifts=(time(6),),
    )
    noise = next(p for p in report.parameters if p.name == "pose_noise_x")
    assert noise.count == 5 * POSES_PER_RUN
    assert noise.cpk is not None
    [day] = report.trend
    [shift] = report.shift_trend
    assert day.cpk["pose_noise_x"] == pytest.approx(noise.cpk, rel=1e-9)
    assert shift.cpk["pose_noise_x"] == pytest.approx(noise.cpk, rel=1e-9)


def _u(offset: float, sensitivity: float) -> dict[str, object]:
    return {
        "k": 2.0,
        "offset": {"x": offset, "y": offset, "z": offset},
        "sensitivity": {"x": sensitivity, "y": sensitivity, "z": sensitivity},
    }


def test_the_report_counts_units_accepted_within_one_u_of_a_limit(session: Session) -> None:
    profile = load_profile()
    high = profile.offset_counts.upper
    low = profile.sensitivity_counts_per_g.lower
    assert high is not None
    assert low is not None
    repository = RunRepository(session)
    runs = [  # serial, verdict, offset x, sensitivity x, uncertainty
        ("U1", "pass", high - 0.5, 815.0, _u(1.0, 0.3)),  # offset within U of the upper
        ("U1", "pass", high - 0.5, 815.0, _u(0.4, 0.3)),  # retest: U smaller, inside
        ("U2", "pass", 2050.0, 815.0, _u(1.0, 0.3)),  # far from every limit
        ("U3", "pass", high - 0.5, 815.0, None),  # no uncertainty recorded: not judged
        ("U4", "pass", 2050.0, low + 0.2, _u(0.1, 0.3)),  # sensitivity within U of lower
        ("U5", "fail", high + 5.0, 815.0, _u(1.0, 0.3)),  # refused anyway: not counted
    ]
    for minute, (serial, verdict, offset_x, sens_x, u) in enumerate(runs):
        failures = (
            [{"code": "offset", "message": "offset x out of limits", "axis": "x"}]
            if verdict == "fail"
            else []
        )
        repository.submit(
            make_record(
                serial=serial,
                verdict=verdict,
                started_at=T0 + timedelta(minutes=minute),
                offset=(offset_x, 2041.2, 1960.5),
                sensitivity=(sens_x, 815.66, 820.17),
                failures=failures,
                **({"uncertainty": u} if u is not None else {}),
            )
        )
    session.commit()
    report = eol_report(session, ReportFilter())
    near = report.near_limits
    assert near is not None
    assert (near.runs_passed, near.within_u, near.units) == (4, 2, 2)
    for shown in (render(report, "text"), render(report, "html")):
        assert "Accepted within one U of a limit: 2 of 4 passing runs" in shown
    assert ("near_limits", "", "within_u", 2) in list(rows(report))
    # The decision risks of each coefficient, from its spread and the runs' mean U/k.
    risks = {r.name: r for r in near.risks}
    assert set(risks) == {f"{f}_{a}" for f in ("offset", "sensitivity") for a in "xyz"}
    assert risks["offset_y"].u == pytest.approx((1.0 + 0.4 + 1.0 + 0.1) / 4 / 2)  # U/k
    for r in near.risks:
        assert 0.0 <= r.guarded_false_accept <= r.simple_false_accept + 1e-12
        assert r.guarded_false_reject >= r.simple_false_reject - 1e-12
        # The risks say what they assume; four runs are too few to check it.
        assert r.assumes == "normal population"
        assert (r.normality_statistic, r.normal, r.normality_values) == (None, None, 0)
    assert "guarded: false accept" in render(report, "text")
