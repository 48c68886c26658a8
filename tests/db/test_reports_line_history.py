"""The end-of-line report's numbers on the hand-built line history of
:mod:`tests.db.eol_data`, on SQLite and PostgreSQL.

The history is stored once per backend for the module, in an outer transaction rolled
back at its end; each test reads it on a savepoint rolled back after the test, so what
a test stores (the golden unit checks) never reaches the next. Every test of the module
works on that one connection: on SQLite no other connection of the module writes while
its transaction is open. The report over the history's range is computed once too.
"""

import itertools
import math
import statistics
from collections.abc import Iterator
from datetime import date, datetime, time, timedelta
from zoneinfo import ZoneInfo

import pytest
from sqlalchemy import Connection
from sqlalchemy.orm import Session

from db import Database, RunRepository
from db.report.reports import eol_report
from db.rollups import rebuild
from station.domain.product.limits import load_profile
from station.domain.quality.figures import EolReport, ReportFilter
from station.domain.quality.parameters import profile_bounds
from tests.db.eol_data import IN_RANGE, RUNS, SINCE, UNTIL, insert_line_history
from tests.db.records import POSES_PER_RUN, RUN_SECONDS, T0, make_record


@pytest.fixture(scope="module")
def history_connection(migrated_database: Database) -> Iterator[Connection]:
    """A connection whose outer transaction holds the line history (stored through the
    repository, roll-ups and all), rolled back after the module's last test."""
    with migrated_database.engine.connect() as connection:
        outer = connection.begin()
        with Session(bind=connection, join_transaction_mode="create_savepoint") as session:
            insert_line_history(session)
        yield connection
        outer.rollback()


@pytest.fixture
def history(history_connection: Connection) -> Iterator[Session]:
    """A session on the line history whose commits are savepoints of one rolled back
    after the test."""
    savepoint = history_connection.begin_nested()
    with Session(bind=history_connection, join_transaction_mode="create_savepoint") as session:
        yield session
    savepoint.rollback()


@pytest.fixture(scope="module")
def line_report(history_connection: Connection) -> EolReport:
    """The report over the history's range (frozen: the tests share it, and only read)."""
    with Session(bind=history_connection, join_transaction_mode="create_savepoint") as session:
        return eol_report(session, ReportFilter(since=SINCE, until=UNTIL))


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


def test_control_chart_points_are_the_latest_runs(history: Session) -> None:
    report = eol_report(history, ReportFilter(since=SINCE, until=UNTIL), chart_points=3)
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


def test_filters_by_station_and_operator(history: Session) -> None:
    st1 = eol_report(history, ReportFilter(since=SINCE, until=UNTIL, station_id="st1"))
    assert (st1.summary.runs, st1.summary.units_tested, st1.summary.units_passed) == (4, 3, 2)
    assert {u.serial for u in st1.units} == {"U1", "U2", "U5"}
    op_b = eol_report(history, ReportFilter(since=SINCE, until=UNTIL, operator_id="op-b"))
    assert (op_b.summary.runs, op_b.summary.first_pass_units) == (4, 1)
    assert [(e.code, e.count) for e in op_b.pareto] == [("offset", 2), ("verification_error", 1)]
    everything = eol_report(history, ReportFilter())
    assert everything.summary.runs == 8
    assert everything.units_total == 6


def test_golden_unit_checks_are_stored_marked_and_never_counted(
    history: Session, line_report: EolReport
) -> None:
    without = line_report
    repository = RunRepository(history)
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
    history.commit()
    stored = repository.get(golden[0].run_id)
    assert stored is not None
    assert stored.purpose == "golden"
    with_golden = eol_report(history, ReportFilter(since=SINCE, until=UNTIL))
    assert with_golden.summary == without.summary
    assert with_golden.pareto == without.pareto
    assert with_golden.parameters == without.parameters
    assert with_golden.control_charts == without.control_charts
    assert with_golden.units == without.units
    rebuild(history.connection())
    rebuilt = eol_report(history, ReportFilter(since=SINCE, until=UNTIL))
    assert (rebuilt.summary, rebuilt.pareto, rebuilt.parameters) == (
        without.summary,
        without.pareto,
        without.parameters,
    )


@pytest.mark.parametrize("zone", ["UTC", "Pacific/Kiritimati"])
def test_the_trend_counts_the_plants_days(history: Session, zone: str) -> None:
    """Kiritimati is UTC+14: the runs of the hand-built history (08:00–09:00 UTC) fall on
    22:00–23:00 local, and U9's (13:00 UTC) on the next local day."""
    report = eol_report(history, ReportFilter(), zone=zone)
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
    history: Session, zone: str, shifts: tuple[time, ...]
) -> None:
    """Each run's shift recomputed from its local start time: the latest start at or
    before it, on its day or (before the day's first) the day before."""
    report = eol_report(history, ReportFilter(), zone=zone, shifts=shifts)
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
    assert eol_report(history, ReportFilter(), zone=zone).shift_trend == []
