"""The report's roll-ups stay exact: random line histories, submitted in random order.

Each history (retests, several stations, operators and lots, runs over three days) is
submitted in a shuffled order, so runs arrive late and retests land before the runs
they follow; some runs are operator aborts, which are a unit's latest run only when all its
runs are. The report, which adds up roll-ups and partial days, must then equal the
definitions computed here straight from the runs; rebuilding the roll-ups from the raw
tables must give the rows the submissions left.
"""

import math
import statistics
from dataclasses import dataclass, replace
from datetime import UTC, date, datetime, time, timedelta
from itertools import pairwise
from typing import Any
from zoneinfo import ZoneInfo

import pytest
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st
from sqlalchemy import select
from sqlalchemy.orm import Session

from db import Database, RunRepository
from db.models import ReportCounts, ReportFailures, ReportParameters, Run, RunFacts, RunFailure
from db.reports import eol_report
from db.rollups import PER_POSE, PER_RUN, _inline, rebuild
from station.domain.limits import Bounds, load_profile
from station.domain.quality.figures import EolReport, ReportFilter
from station.domain.quality.parameters import PARAMETERS
from tests.conftest import examples
from tests.databases import rolled_back
from tests.db.records import T0, make_record

DAY0 = T0.replace(hour=0)
PRODUCTS = ("DIXX-A12", "DIXX-D16")
MOMENTS = [None, DAY0, DAY0 + timedelta(days=1), T0 + timedelta(hours=20), DAY0 + timedelta(days=3)]


@dataclass(frozen=True)
class Planned:
    """One run of a generated history."""

    serial: str
    part_number: str
    station: str
    operator: str
    lot: str | None
    started_at: datetime
    code: str | None
    charted: bool
    offset_x: float

    @property
    def passed(self) -> bool:
        return self.code is None


@st.composite
def histories(draw: st.DrawFn) -> list[Planned]:
    """Up to 12 runs of up to 4 units (each of one of two products) over three days, each
    start a distinct minute."""
    minutes = draw(st.lists(st.integers(0, 3 * 24 * 60), min_size=1, max_size=12, unique=True))
    products = {s: draw(st.sampled_from(PRODUCTS)) for s in ("U1", "U2", "U3", "U4")}
    runs = []
    for minute in minutes:
        code = draw(st.sampled_from([None, None, "offset", "sensitivity", "aborted"]))
        serial = draw(st.sampled_from(sorted(products)))
        runs.append(
            Planned(
                serial=serial,
                part_number=products[serial],
                station=draw(st.sampled_from(["st1", "st2"])),
                operator=draw(st.sampled_from(["op-a", "op-b"])),
                lot=draw(st.sampled_from([None, "L1", "L2"])),
                started_at=T0 + timedelta(minutes=minute),
                code=code,
                charted=code is None or draw(st.booleans()),
                offset_x=float(draw(st.integers(1800, 2300))),
            )
        )
    return runs


filters = st.builds(
    ReportFilter,
    since=st.sampled_from(MOMENTS[:4]),
    until=st.sampled_from([None, *MOMENTS[2:]]),
    station_id=st.sampled_from([None, "st1"]),
    operator_id=st.sampled_from([None, "op-b"]),
    lot=st.sampled_from([None, "L1"]),
    part_number=st.sampled_from([None, "DIXX-D16"]),
)


def _record(run: Planned) -> Any:
    failures = [] if run.code is None else [{"code": run.code, "message": "out of limits"}]
    extra: dict[str, Any] = {} if run.charted else {"coefficients": None, "quality": None}
    return make_record(
        serial=run.serial,
        part_number=run.part_number,
        station_id=run.station,
        verdict="pass" if run.passed else "fail",
        started_at=run.started_at,
        offset=(run.offset_x, 2048.0, 1960.5),
        operator_id=run.operator,
        lot=run.lot,
        failures=failures,
        **extra,
    )


def _selected(run: Planned, f: ReportFilter) -> bool:
    return (
        (f.since is None or run.started_at >= f.since)
        and (f.until is None or run.started_at < f.until)
        and f.station_id in (None, run.station)
        and f.operator_id in (None, run.operator)
        and f.lot in (None, run.lot)
        and f.part_number in (None, run.part_number)
    )


def _expected_counts(
    history: list[Planned], chosen: list[Planned], same: Any
) -> tuple[int, int, int, int, int]:
    """(runs, passed, units, first passes, final passes), units counted at their first
    run among the runs ``same`` groups with it, not the units with nothing but aborts."""
    first = [r for r in chosen if r == min((o for o in history if same(o, r)), key=_start)]
    latest = {id(r): max((o for o in history if same(o, r)), key=_latest) for r in first}
    # a unit with nothing but aborts (its latest run is one) was never attempted
    first = [r for r in first if latest[id(r)].code != "aborted"]
    return (
        len(chosen),
        sum(r.passed for r in chosen),
        len(first),
        sum(r.passed for r in first),
        sum(latest[id(r)].passed for r in first),
    )


def _start(run: Planned) -> datetime:
    return run.started_at


def _latest(run: Planned) -> tuple[bool, datetime]:
    """Order of a unit's latest run: an operator's abort only when all its runs are."""
    return (run.code != "aborted", run.started_at)


def _check_group(summary: Any, history: list[Planned], runs: list[Planned], same: Any) -> None:
    """A row of the report (a station's, a product's) against its ``runs``: the counts,
    the operator's aborts and the retests."""
    assert _counts_of(summary) == _expected_counts(history, runs, same)
    aborts = sum(r.code == "aborted" for r in runs)
    assert summary.aborted_runs == aborts
    assert summary.retests == max(0, len(runs) - aborts - summary.units_tested)


def _counts_of(summary: Any) -> tuple[int, int, int, int, int]:
    return (
        summary.runs,
        summary.runs_passed,
        summary.units_tested,
        summary.first_pass_units,
        summary.units_passed,
    )


def _check(report: EolReport, history: list[Planned], f: ReportFilter) -> None:
    chosen = sorted((r for r in history if _selected(r, f)), key=_start)

    def unit(a: Planned, b: Planned) -> bool:
        return a.serial == b.serial

    assert _counts_of(report.summary) == _expected_counts(history, chosen, unit)
    assert report.summary.poses == 7 * len(chosen)
    stations = {s.station_id: s.summary for s in report.stations}
    assert sorted(stations) == sorted({r.station for r in chosen})
    for station, summary in stations.items():
        # A station's row: the units whose first run on the line was there (and is
        # selected), their first and final passes, and every run at the station.
        _check_group(summary, history, [r for r in chosen if r.station == station], unit)
    # So the rows add up to the "all" row, on a filtered page too.
    for field in ("runs", "runs_passed", "units_tested", "first_pass_units", "units_passed"):
        assert sum(getattr(s, field) for s in stations.values()) == getattr(report.summary, field)
    products = {p.part_number: p.summary for p in report.products}
    assert sorted(products) == sorted({r.part_number for r in chosen})
    for part_number, summary in products.items():
        # A product's row: its units (a unit is one product's) and its runs.
        of = [r for r in chosen if r.part_number == part_number]
        _check_group(summary, history, of, unit)
        assert summary.poses == 7 * len(of)
    _check_trend(report, history, chosen)
    # an operator's abort is no failure category
    codes = [r.code for r in chosen if r.code not in (None, "aborted")]
    assert {e.code: e.count for e in report.pareto} == {c: codes.count(c) for c in set(codes)}
    # the units listed are the units counted: first run selected, not only aborts
    latest = {r.serial: r for r in sorted(history, key=_latest)}
    first = {r.serial: r for r in sorted(history, key=_start, reverse=True)}
    listed = {
        serial for serial, r in first.items() if r in chosen and latest[serial].code != "aborted"
    }
    assert report.units_total == report.summary.units_tested == len(listed)
    assert {u.serial for u in report.units} == listed
    held = {u.serial for u in report.units if u.disposition == "hold"}
    assert report.units_held == report.summary.units_failed == len(held)

    xs = [r.offset_x for r in chosen if r.charted]
    params = {p.name: p for p in report.parameters}
    x = params["offset_x"]
    assert (x.count, x.min, x.max) == (len(xs), min(xs, default=None), max(xs, default=None))
    assert params["pose_noise_x"].count == 7 * len(chosen)
    if xs:
        assert x.mean == pytest.approx(statistics.mean(xs), rel=1e-12)
    if len(xs) > 1:
        assert x.std == pytest.approx(statistics.stdev(xs), rel=1e-9, abs=1e-9)
    lower, upper = x.lower, x.upper
    assert lower is not None
    assert upper is not None
    assert x.out_of_limits == sum(not lower <= v <= upper for v in xs)
    h = x.histogram
    bins = [min(max(math.floor((v - h.start) / h.width), 0), len(h.counts) - 1) for v in xs]
    assert h.counts == [bins.count(i) for i in range(len(h.counts))]

    charts = {c.name: c for c in report.control_charts}
    if not xs:
        assert charts == {}
        return
    chart = charts["offset_x"]
    assert (chart.count, chart.mean) == (len(xs), pytest.approx(statistics.mean(xs)))
    if len(xs) > 1:
        mr_bar = statistics.mean(abs(b - a) for a, b in pairwise(xs))
        assert chart.mr_bar == pytest.approx(mr_bar, rel=1e-9, abs=1e-9)
    else:
        assert chart.mr_bar is None


def _check_trend(report: EolReport, history: list[Planned], chosen: list[Planned]) -> None:
    """Each plant day's units (first run on the line that day), yields and Cpk."""
    zone = ZoneInfo(report.timezone)
    days = [d.day for d in report.trend]
    assert days == sorted(days)
    assert all((b - a).days == 1 for a, b in pairwise(days))

    def day_of(run: Planned) -> date:
        return run.started_at.astimezone(zone).date()

    assert {day_of(r) for r in chosen} <= set(days)
    for trend_day in report.trend:
        that_day = [r for r in chosen if day_of(r) == trend_day.day]
        runs, passed, units, first, final = _expected_counts(
            history, that_day, lambda a, b: a.serial == b.serial
        )
        assert (trend_day.runs, trend_day.runs_passed, trend_day.units) == (runs, passed, units)
        assert trend_day.first_pass_yield == (first / units if units else None)
        assert trend_day.final_yield == (final / units if units else None)
        xs = [r.offset_x for r in that_day if r.charted]
        params = {p.name: p for p in report.parameters}
        lower, upper = params["offset_x"].lower, params["offset_x"].upper
        assert lower is not None
        assert upper is not None
        if len(xs) > 1 and statistics.stdev(xs) > 0:
            mean, std = statistics.mean(xs), statistics.stdev(xs)
            expected = min(upper - mean, mean - lower) / (3 * std)
            assert trend_day.cpk["offset_x"] == pytest.approx(expected, rel=1e-9)
        elif len(xs) < 2:
            assert trend_day.cpk["offset_x"] is None
    assert sum(d.units for d in report.trend) == report.summary.units_tested
    assert sum(d.runs for d in report.trend) == report.summary.runs
    for shift in report.shift_trend:
        in_shift = [r for r in chosen if shift.start <= r.started_at < shift.end]
        runs, passed, units, first, final = _expected_counts(
            history, in_shift, lambda a, b: a.serial == b.serial
        )
        assert (shift.runs, shift.runs_passed, shift.units) == (runs, passed, units)
        assert shift.first_pass_yield == (first / units if units else None)
        assert shift.final_yield == (final / units if units else None)
    if report.shift_trend:
        assert sum(s.units for s in report.shift_trend) == report.summary.units_tested
        assert sum(s.runs for s in report.shift_trend) == report.summary.runs


def stored_verdicts(session: Session) -> list[tuple[Any, ...]]:
    """Every run's verdict and failures as stored."""
    runs = session.execute(select(Run.id, Run.verdict).order_by(Run.id)).all()
    failures = session.execute(
        select(RunFailure.run_pk, RunFailure.position, RunFailure.code).order_by(
            RunFailure.run_pk, RunFailure.position
        )
    ).all()
    return [*map(tuple, runs), *map(tuple, failures)]


def _check_what_if(report: EolReport, history: list[Planned], f: ReportFilter) -> None:
    """Against offsets 1900…2200: a run would fail on its offset outside them, an abort
    stays an abort, and every other stored reason (offset, sensitivity against the
    generous defaults) is judged again on the stored values, which pass."""

    def judged(run: Planned) -> Planned:
        if run.code == "aborted":
            return run
        outside = run.charted and not 1900.0 <= run.offset_x <= 2200.0
        return replace(run, code="offset" if outside else None)

    again = [judged(r) for r in history]
    chosen = sorted((r for r in again if _selected(r, f)), key=_start)
    what_if = report.what_if
    assert what_if is not None
    assert (
        what_if.limits.sha256 != report.limits_profiles[0].sha256
        if report.limits_profiles
        else True
    )
    expected = _expected_counts(again, chosen, lambda a, b: a.serial == b.serial)
    assert _counts_of(what_if.summary) == expected
    codes = [r.code for r in chosen if r.code not in (None, "aborted")]
    assert {e.code: e.count for e in what_if.pareto} == {c: codes.count(c) for c in set(codes)}
    before = sorted((r for r in history if _selected(r, f)), key=_start)
    pairs = list(zip(before, chosen, strict=True))
    assert what_if.pass_to_fail == sum(a.passed and not b.passed for a, b in pairs)
    assert what_if.fail_to_pass == sum(b.passed and not a.passed for a, b in pairs)
    xs = [r.offset_x for r in chosen if r.charted]
    x = next(p for p in what_if.parameters if p.name == "offset_x")
    assert (x.lower, x.upper, x.count) == (1900.0, 2200.0, len(xs))
    assert x.out_of_limits == sum(not 1900.0 <= v <= 2200.0 for v in xs)
    h = x.histogram
    bins = [min(max(math.floor((v - h.start) / h.width), 0), len(h.counts) - 1) for v in xs]
    assert h.counts == [bins.count(i) for i in range(len(h.counts))]


def rollup_rows(session: Session) -> dict[str, set[tuple[Any, ...]]]:
    """Every roll-up and fact row, floats rounded to 6 digits (sums in another order)."""

    def rounded(row: Any) -> tuple[Any, ...]:
        return tuple(round(v, 6) if isinstance(v, float) else v for v in row)

    tables = (RunFacts, ReportCounts, ReportFailures, ReportParameters)
    return {
        t.__tablename__: {rounded(row) for row in session.execute(select(t.__table__))}
        for t in tables
    }


@pytest.mark.timeout(400)  # a safety net: 30 histories, each with its trend and what-if
@settings(
    max_examples=examples(30),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
    phases=[Phase.explicit, Phase.reuse, Phase.generate, Phase.shrink],
)
@given(
    history=histories(),
    order=st.randoms(use_true_random=False),
    report_filter=filters,
    narrower=st.booleans(),
    zone=st.sampled_from(["UTC", "America/New_York", "Asia/Kolkata"]),
    shifts=st.sampled_from([(), (time(6), time(14), time(22)), (time(7, 30), time(19, 30))]),
)
def test_late_runs_and_retests_keep_the_report_exact(
    migrated_database: Database,
    history: list[Planned],
    order: Any,
    report_filter: ReportFilter,
    narrower: bool,
    zone: str,
    shifts: tuple[time, ...],
) -> None:
    """``narrower``: capability against offset limits other than the roll-ups' bins."""
    submitted = list(history)
    order.shuffle(submitted)
    with rolled_back(migrated_database) as session:
        repository = RunRepository(session)
        for run in submitted:
            repository.submit(_record(run))
        session.flush()
        candidate = None
        if narrower:
            offset = Bounds(lower=1900.0, upper=2200.0)
            candidate = load_profile().model_copy(update={"offset_counts": offset})
        before = stored_verdicts(session)
        report = eol_report(session, report_filter, candidate=candidate, zone=zone, shifts=shifts)
        assert stored_verdicts(session) == before  # the what-if changes nothing stored
        offset_x = next(p for p in report.parameters if p.name == "offset_x")
        assert offset_x.lower == 1841.0
        _check(report, history, report_filter)
        if candidate is not None:
            _check_what_if(report, history, report_filter)
        else:
            assert report.what_if is None
        kept = rollup_rows(session)
        rebuild(session.connection())
        assert rollup_rows(session) == kept


@settings(max_examples=examples(200), deadline=None)
@given(
    value=st.one_of(
        st.floats(allow_nan=False, allow_infinity=False),
        st.integers(-(2**31), 2**31 - 1),
        st.text(alphabet="abcxyz_.-019", max_size=12),
    )
)
def test_constants_written_into_the_statements_read_back_unchanged(
    migrated_database: Database, value: float | str
) -> None:
    with migrated_database.engine.connect() as connection:
        assert connection.scalar(select(_inline(value))) == value


@pytest.mark.parametrize("text", ["it's", "a;b", "x y", "é"])
def test_text_that_is_not_a_plain_constant_is_refused(text: str) -> None:
    with pytest.raises(ValueError, match="not a constant"):
        _inline(text)


def test_every_report_parameter_is_stored_in_exactly_one_column() -> None:
    stored = [*PER_RUN, *PER_POSE]
    assert sorted(stored) == sorted(spec.name for spec in PARAMETERS)
    assert len(set(stored)) == len(stored)


#: The last moment a stored time can hold: SQLite's date functions round it into 10000.
LAST_MOMENT = datetime(9999, 12, 31, 23, 59, 59, 999999, tzinfo=UTC)


def test_runs_of_one_unit_in_the_year_1_and_the_last_moment_of_9999_are_rolled_up(
    session: Session,
) -> None:
    """A station's own database takes any time of the years 1…9999 (only the results
    server refuses implausible ones): the roll-ups count either, to the millisecond."""
    first = make_record(started_at=datetime(1, 1, 1, tzinfo=UTC))
    last = make_record(
        started_at=LAST_MOMENT - timedelta(seconds=95, milliseconds=250),
        finished_at=LAST_MOMENT.isoformat(),
        verdict="fail",
    )
    repository = RunRepository(session)
    for record in (first, last):
        repository.submit(record)
    session.flush()
    counts = session.execute(
        select(ReportCounts.day, ReportCounts.duration_ms).order_by(ReportCounts.day)
    ).all()
    days = [(d.date() - date(1970, 1, 1)).days for d in (first.started_at, last.started_at)]
    assert [tuple(row) for row in counts] == [(days[0], 95_000), (days[1], 95_250)]
    report = eol_report(session, ReportFilter())
    assert (report.summary.runs, report.summary.cycle_time_per_run_s) == (2, 95.125)
    kept = rollup_rows(session)
    rebuild(session.connection())
    assert rollup_rows(session) == kept
