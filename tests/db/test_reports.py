"""The end-of-line report's numbers on a hand-built line history, on SQLite and PostgreSQL."""

import itertools
import math
import statistics
from datetime import date, datetime, time, timedelta
from zoneinfo import ZoneInfo

import pytest
from sqlalchemy.orm import Session

from db import Database, RunQuery, RunRepository
from db.reports import eol_report
from db.rollups import rebuild
from station.domain.limits import load_profile
from station.domain.quality.figures import EolReport, ReportFilter
from station.domain.quality.parameters import profile_bounds
from station.report.render import render, rows
from tests.databases import rolled_back
from tests.db.eol_data import IN_RANGE, RUNS, SINCE, UNTIL, insert_line_history
from tests.db.records import T0, make_record

RUN_SECONDS = 95.0  # every test run lasts 95 s
POSES_PER_RUN = 7


def _report(session: Session) -> EolReport:
    """The report over the range of the line history, stored in ``session``."""
    insert_line_history(session)
    return eol_report(session, ReportFilter(since=SINCE, until=UNTIL))


@pytest.fixture(scope="module")
def line_report(migrated_database: Database) -> EolReport:
    """:func:`_report` once per backend, in a transaction rolled back after it: the tests
    that only read the report share it (it is frozen) instead of storing the history and
    computing it again each."""
    with rolled_back(migrated_database) as session:
        return _report(session)


def test_counts_and_yields_over_the_range(line_report: EolReport) -> None:
    s = line_report.summary
    # 7 runs in range (U9's is after it); passes: U1, U4, U2's retest.
    assert (s.runs, s.runs_passed) == (7, 3)
    assert s.report_yield == pytest.approx(3 / 7)
    # Units U1…U5; first runs passed: U1, U4; latest runs passed: U1, U2, U4.
    assert (s.units_tested, s.first_pass_units, s.units_passed, s.units_failed) == (5, 2, 3, 2)
    assert s.first_pass_yield == pytest.approx(2 / 5)
    assert s.final_yield == pytest.approx(3 / 5)
    assert (s.retests, s.retest_rate) == (2, pytest.approx(2 / 5))
    assert s.hours == pytest.approx(2.0)
    # per hour of station time, as the cycle times: 3600 / (7 runs' time / 5 units)
    assert s.units_per_hour == pytest.approx(3600 * 5 / (7 * RUN_SECONDS))
    assert s.cycle_time_per_run_s == pytest.approx(RUN_SECONDS)
    assert s.cycle_time_per_unit_s == pytest.approx(7 * RUN_SECONDS / 5)
    assert s.poses == 7 * POSES_PER_RUN
    assert s.cycle_time_per_pose_s == pytest.approx(RUN_SECONDS / POSES_PER_RUN)


def test_per_station_summaries_rank_units_within_the_station(line_report: EolReport) -> None:
    stations = {s.station_id: s.summary for s in line_report.stations}
    assert sorted(stations) == ["st1", "st2"]
    st1, st2 = stations["st1"], stations["st2"]
    # st1: U1 pass; U2 fail then pass; U5 fail.
    assert (st1.runs, st1.units_tested, st1.first_pass_units, st1.units_passed) == (4, 3, 1, 2)
    # st2: U3 fail, fail; U4 pass.
    assert (st2.runs, st2.units_tested, st2.first_pass_units, st2.units_passed) == (3, 2, 1, 1)
    assert st2.first_pass_yield == pytest.approx(1 / 2)


def test_pareto_counts_each_failing_runs_first_reason(line_report: EolReport) -> None:
    pareto = line_report.pareto
    assert [(e.code, e.count) for e in pareto] == [
        ("offset", 2),
        ("sensitivity", 1),
        ("verification_error", 1),
    ]
    offset = pareto[0]
    assert (offset.share, offset.cumulative_share) == (pytest.approx(0.5), pytest.approx(0.5))
    assert offset.by_station == {"st1": 1, "st2": 1}
    assert offset.by_operator == {"op-b": 2}
    assert pareto[-1].cumulative_share == pytest.approx(1.0)
    assert "link_loss" not in {e.code for e in pareto}


def test_capability_of_the_offsets_against_the_datasheet_bounds(line_report: EolReport) -> None:
    lower, upper = profile_bounds(load_profile())["offset"]
    assert (lower, upper) == (1841.0, 2255.0)
    params = {p.name: p for p in line_report.parameters}
    xs = [run[5] for run in IN_RANGE]
    mean, std = statistics.mean(xs), statistics.stdev(xs)
    x = params["offset_x"]
    assert (x.count, x.min, x.max) == (7, 2040.0, 2060.0)
    assert x.mean == pytest.approx(mean, rel=1e-12)
    assert x.std == pytest.approx(std, rel=1e-9)
    assert x.cp == pytest.approx((upper - lower) / (6 * std), rel=1e-9)
    assert x.cpk == pytest.approx(min(upper - mean, mean - lower) / (3 * std), rel=1e-9)
    assert (x.out_of_limits, x.marginal) == (0, 0)
    # offset_y: 2260 is outside; 2240 lies within 10 % of the 414-count width of 2255.
    y = params["offset_y"]
    assert (y.out_of_limits, y.marginal) == (1, 1)
    ys = [run[6] for run in IN_RANGE]
    assert y.cpk == pytest.approx(
        (upper - statistics.mean(ys)) / (3 * statistics.stdev(ys)), rel=1e-9
    )


def test_histograms_count_every_value_once_in_its_bin(line_report: EolReport) -> None:
    params = {p.name: p for p in line_report.parameters}
    y = params["offset_y"].histogram
    assert sum(y.counts) == 7
    assert y.start == pytest.approx(1841 - 414 / 4)
    for value, expected in ((2048.0, 5), (2240.0, 1), (2260.0, 1)):
        assert y.counts[math.floor((value - y.start) / y.width)] == expected
    noise = params["pose_noise_x"]
    assert (noise.count, noise.mean, noise.upper) == (49, pytest.approx(1.1), 8.0)
    assert noise.cp is None  # one-sided limit
    bias = params["gyro_bias_x"]
    assert (bias.count, bias.mean) == (7, pytest.approx(0.01))


def test_control_chart_limits_from_moving_ranges_in_time_order(line_report: EolReport) -> None:
    chart = next(c for c in line_report.control_charts if c.name == "offset_x")
    xs = [run[5] for run in IN_RANGE]
    mr_bar = statistics.mean(abs(b - a) for a, b in itertools.pairwise(xs))
    assert chart.count == 7
    assert chart.mean == pytest.approx(statistics.mean(xs))
    assert chart.mr_bar == pytest.approx(mr_bar)
    assert chart.ucl == pytest.approx(statistics.mean(xs) + 2.66 * mr_bar, rel=1e-3)
    assert chart.mr_ucl == pytest.approx(3.267 * mr_bar)
    assert [p.value for p in chart.points] == xs
    assert [p.moving_range for p in chart.points][1:] == pytest.approx(
        [abs(b - a) for a, b in itertools.pairwise(xs)]
    )


def test_control_chart_points_are_the_latest_runs(session: Session) -> None:
    insert_line_history(session)
    report = eol_report(session, ReportFilter(since=SINCE, until=UNTIL), chart_points=3)
    chart = report.control_charts[0]
    assert [p.serial for p in chart.points] == ["U5", "U2", "U3"]
    assert chart.points[0].moving_range == pytest.approx(10.0)  # 2055 after U4's 2045
    assert chart.count == 7


def test_units_list_gives_each_units_final_disposition(line_report: EolReport) -> None:
    units = {u.serial: u for u in line_report.units}
    assert line_report.units_total == 5
    assert {s: u.disposition for s, u in units.items()} == {
        "U1": "ship",
        "U2": "ship",
        "U3": "hold",
        "U4": "ship",
        "U5": "hold",
    }
    assert (units["U3"].runs, units["U3"].failure) == (2, "verification_error")
    # newest first run first (the order the yield table counts them in)
    assert [u.serial for u in line_report.units][:2] == ["U5", "U4"]


def test_filters_by_station_and_operator(session: Session) -> None:
    insert_line_history(session)
    st1 = eol_report(session, ReportFilter(since=SINCE, until=UNTIL, station_id="st1"))
    assert (st1.summary.runs, st1.summary.units_tested, st1.summary.units_passed) == (4, 3, 2)
    assert {u.serial for u in st1.units} == {"U1", "U2", "U5"}
    op_b = eol_report(session, ReportFilter(since=SINCE, until=UNTIL, operator_id="op-b"))
    assert (op_b.summary.runs, op_b.summary.first_pass_units) == (4, 1)
    assert [(e.code, e.count) for e in op_b.pareto] == [("offset", 2), ("verification_error", 1)]
    everything = eol_report(session, ReportFilter())
    assert everything.summary.runs == 8
    assert everything.units_total == 6


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


def test_golden_unit_checks_are_stored_marked_and_never_counted(session: Session) -> None:
    without = _report(session)
    repository = RunRepository(session)
    golden = [
        make_record(serial="GU-001", purpose="golden", started_at=SINCE + timedelta(minutes=m))
        for m in (5, 65)
    ]
    golden.append(
        make_record(
            serial="GU-001",
            purpose="golden",
            verdict="fail",
            offset=(2300.0, 2041.2, 1960.5),
            started_at=SINCE + timedelta(minutes=95),
        )
    )
    for record in golden:
        repository.submit(record)
    session.commit()
    stored = repository.get(golden[0].run_id)
    assert stored is not None
    assert stored.purpose == "golden"
    with_golden = eol_report(session, ReportFilter(since=SINCE, until=UNTIL))
    assert with_golden.summary == without.summary
    assert with_golden.pareto == without.pareto
    assert with_golden.parameters == without.parameters
    assert with_golden.control_charts == without.control_charts
    assert with_golden.units == without.units
    rebuild(session.connection())
    rebuilt = eol_report(session, ReportFilter(since=SINCE, until=UNTIL))
    assert (rebuilt.summary, rebuilt.pareto, rebuilt.parameters) == (
        without.summary,
        without.pareto,
        without.parameters,
    )


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


@pytest.mark.parametrize("zone", ["UTC", "Pacific/Kiritimati"])
def test_the_trend_counts_the_plants_days(session: Session, zone: str) -> None:
    """Kiritimati is UTC+14: the runs of the hand-built history (08:00–09:00 UTC) fall on
    22:00–23:00 local, and U9's (13:00 UTC) on the next local day."""
    insert_line_history(session)
    report = eol_report(session, ReportFilter(), zone=zone)
    local = ZoneInfo(zone)
    by_day: dict[date, list[tuple[int, str]]] = {}
    for minute, serial, *_ in RUNS:
        started = (T0 + timedelta(minutes=minute)).astimezone(local).date()
        by_day.setdefault(started, []).append((minute, serial))
    assert [d.day for d in report.trend] == sorted(by_day)
    assert len(report.trend) == (2 if zone != "UTC" else 1)
    for trend_day in report.trend:
        runs = by_day[trend_day.day]
        assert trend_day.runs == len(runs)
        firsts = {serial for _, serial in runs} - {
            serial for m, serial, *_ in RUNS if m < min(m for m, _ in runs)
        }
        assert trend_day.units == len(firsts)
    assert report.timezone == zone


@pytest.mark.parametrize(
    ("zone", "shifts"),
    [
        ("UTC", (time(8, 25), time(12), time(22))),
        ("Europe/Berlin", (time(6), time(9, 35), time(14))),
    ],
)
def test_the_shift_trend_counts_each_shifts_runs_and_units(
    session: Session, zone: str, shifts: tuple[time, ...]
) -> None:
    """Each run's shift recomputed from its local start time: the latest start at or
    before it, on its day or (before the day's first) the day before."""
    insert_line_history(session)
    report = eol_report(session, ReportFilter(), zone=zone, shifts=shifts)
    local = ZoneInfo(zone)

    def shift_of(minute: int) -> tuple[str, str]:
        at = (T0 + timedelta(minutes=minute)).astimezone(local)
        starts = [
            datetime.combine(at.date() + timedelta(days=d), s, tzinfo=local)
            for d in (-1, 0)
            for s in shifts
        ]
        begun = max(s for s in starts if s <= at)
        return (begun.date().isoformat(), begun.strftime("%H:%M"))

    runs: dict[tuple[str, str], int] = {}
    units: dict[tuple[str, str], int] = {}
    seen: set[str] = set()
    for minute, serial, *_ in RUNS:
        key = shift_of(minute)
        runs[key] = runs.get(key, 0) + 1
        if serial not in seen:
            seen.add(serial)
            units[key] = units.get(key, 0) + 1
    found = {(s.day.isoformat(), s.shift): s for s in report.shift_trend}
    assert len(runs) >= 3  # the history spans three shifts at least
    assert {k: s.runs for k, s in found.items() if s.runs} == runs
    assert {k: s.units for k, s in found.items() if s.units} == units
    assert sum(s.units for s in report.shift_trend) == sum(d.units for d in report.trend)
    assert report.shifts == [s.strftime("%H:%M") for s in shifts]
    starts = [s.start for s in report.shift_trend]
    assert starts == sorted(starts)
    assert eol_report(session, ReportFilter(), zone=zone).shift_trend == []


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
    assert "guarded: false accept" in render(report, "text")
