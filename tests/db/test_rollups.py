"""The report's roll-ups stay exact: random line histories, submitted in random order.

Each history (retests at the same or another station, three stations, operators and
lots, runs over three days) is submitted in a shuffled order, so runs arrive late and
retests land before the runs they follow; some runs are operator aborts (a unit's first
run, its latest, or all of them), which are runs but never attempts. The report, which
adds up roll-ups and partial days, must then equal the yield definition computed here
straight from the runs (:func:`expected_figures`, written apart from the SQL of
:mod:`db.rollups`), before and after rebuilding the roll-ups from the raw tables, which
must give the rows the submissions left.
"""

import math
import statistics
from dataclasses import dataclass, fields, replace
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
from db.models import (
    ReportCounts,
    ReportFailures,
    ReportParameters,
    Run,
    RunFacts,
    RunFailure,
    Unit,
)
from db.report.holds import held_units
from db.report.reports import eol_report
from db.rollups import PER_POSE, PER_RUN, _inline, rebuild
from station.domain.errors import InputError
from station.domain.product.limits import Bounds, load_profile
from station.domain.quality.figures import EolReport, ReportFilter
from station.domain.quality.parameters import PARAMETERS
from station.domain.record.unit_state import UnitCalibration
from tests.conftest import examples
from tests.databases import rolled_back
from tests.db.records import T0, make_record

DAY0 = T0.replace(hour=0)
PRODUCTS = ("DIXX-A12", "DIXX-D16")
STATIONS = ("st1", "st2", "st3")
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
    """Up to 12 runs of up to 4 units (each of one of two products) at three stations over
    three days, each start a distinct minute."""
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
                station=draw(st.sampled_from(STATIONS)),
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
    station_id=st.sampled_from([None, "st1", "st2"]),
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


@dataclass(frozen=True)
class Expected:
    """A row of the report by the yield definition, computed from the runs."""

    runs: int
    runs_passed: int
    units: int
    first_pass: int
    final_pass: int
    retests: int
    aborts: int


def _attempt(run: Planned) -> bool:
    """An attempt: a run the operator did not abort."""
    return run.code != "aborted"


def expected_figures(history: list[Planned], chosen: list[Planned]) -> Expected:
    """The figures of the runs ``chosen`` (of ``history``, every run of the line): a unit
    counts where its first attempt ever is, passes first if that attempt passed and
    finally if its latest attempt ever passed; an attempt that is not its unit's first
    is a retest wherever it is; an abort is a run, never an attempt."""
    first: dict[str, Planned] = {}
    latest: dict[str, Planned] = {}
    for run in sorted(filter(_attempt, history), key=_start):
        first.setdefault(run.serial, run)
        latest[run.serial] = run
    cohort = [r for r in chosen if _attempt(r) and first[r.serial] == r]
    return Expected(
        runs=len(chosen),
        runs_passed=sum(r.passed for r in chosen),
        units=len(cohort),
        first_pass=sum(r.passed for r in cohort),
        final_pass=sum(latest[r.serial].passed for r in cohort),
        retests=sum(_attempt(r) and first[r.serial] != r for r in chosen),
        aborts=sum(not _attempt(r) for r in chosen),
    )


def _start(run: Planned) -> datetime:
    return run.started_at


def _latest_attempts(history: list[Planned]) -> dict[str, Planned]:
    """Each attempted unit's latest attempt."""
    return {r.serial: r for r in sorted(filter(_attempt, history), key=_start)}


def _check_group(summary: Any, history: list[Planned], runs: list[Planned]) -> None:
    """A row of the report (the line's, a station's, a product's) against its ``runs``."""
    assert _figures(summary) == expected_figures(history, runs)


def _figures(summary: Any) -> Expected:
    return Expected(
        runs=summary.runs,
        runs_passed=summary.runs_passed,
        units=summary.units_tested,
        first_pass=summary.first_pass_units,
        final_pass=summary.units_passed,
        retests=summary.retests,
        aborts=summary.aborted_runs,
    )


def _check(report: EolReport, history: list[Planned], f: ReportFilter) -> None:
    chosen = sorted((r for r in history if _selected(r, f)), key=_start)
    _check_group(report.summary, history, chosen)
    assert report.summary.poses == 7 * len(chosen)
    stations = {s.station_id: s.summary for s in report.stations}
    assert sorted(stations) == sorted({r.station for r in chosen})
    for station, summary in stations.items():
        # A station's row: the units whose first attempt on the line was there (and is
        # selected), their first and final passes, every run at the station, and its
        # own retests (its attempts that are not their unit's first) and aborts.
        _check_group(summary, history, [r for r in chosen if r.station == station])
    products = {p.part_number: p.summary for p in report.products}
    assert sorted(products) == sorted({r.part_number for r in chosen})
    for part_number, summary in products.items():
        # A product's row: its units (a unit is one product's) and its runs.
        of = [r for r in chosen if r.part_number == part_number]
        _check_group(summary, history, of)
        assert summary.poses == 7 * len(of)
    # So the rows add up to the "all" row, on a filtered page too.
    for rows in (stations.values(), products.values()):
        added = [_figures(row) for row in rows]
        for field in (f.name for f in fields(Expected)):
            total = getattr(_figures(report.summary), field)
            assert sum(getattr(row, field) for row in added) == total
    # an operator's abort is no failure category
    codes = [r.code for r in chosen if r.code not in (None, "aborted")]
    assert {e.code: e.count for e in report.pareto} == {c: codes.count(c) for c in set(codes)}
    # the units listed are the units counted: first attempt selected (never a unit with
    # nothing but aborts), each with its latest attempt
    latest = _latest_attempts(history)
    first = {r.serial: r for r in sorted(filter(_attempt, history), key=_start, reverse=True)}
    listed = {serial for serial, r in first.items() if r in chosen}
    assert report.units_total == report.summary.units_tested == len(listed)
    assert {u.serial: u.last_started_at for u in report.units} == {
        s: latest[s].started_at for s in listed
    }
    held = {s for s in listed if not latest[s].passed}
    assert {u.serial for u in report.units if u.disposition == "hold"} == held
    assert report.units_held == report.summary.units_failed == len(held)
    assert report.open_holds is not None
    assert report.open_holds.total == len(held)  # no review closed any

    zone = ZoneInfo(report.timezone)
    products = {r.part_number for r in chosen}
    if len(products) > 1:
        # No statistic of coefficients spans two products: each has its own section.
        assert (report.parameters, report.control_charts) == ([], [])
        _check_trend(report, history, chosen, zone, charted=False)
        sections = {s.part_number: s for s in report.product_sections}
        assert sorted(sections) == sorted(products)
        for part_number, section in sections.items():
            of = [r for r in chosen if r.part_number == part_number]
            _check_statistics(section, history, of, zone)
    else:
        assert report.product_sections == []
        _check_statistics(report, history, chosen, zone)


def _check_statistics(
    part: Any, history: list[Planned], chosen: list[Planned], zone: ZoneInfo
) -> None:
    """One product's capability, distributions, control charts and trend (the report's
    own when its runs are of one product, else the product's section)."""
    _check_trend(part, history, chosen, zone, charted=True)
    xs = [r.offset_x for r in chosen if r.charted]
    params = {p.name: p for p in part.parameters}
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

    charts = {c.name: c for c in part.control_charts}
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


def _check_trend(
    report: Any, history: list[Planned], chosen: list[Planned], zone: ZoneInfo, *, charted: bool
) -> None:
    """Each plant day's units (first run on the line that day), yields and Cpk in the
    plant's ``zone`` (``charted``: ``report`` holds one product's capability, its own or a
    product section's; else no day has a Cpk)."""
    days = [d.day for d in report.trend]
    assert days == sorted(days)
    assert all((b - a).days == 1 for a, b in pairwise(days))

    def day_of(run: Planned) -> date:
        return run.started_at.astimezone(zone).date()

    assert {day_of(r) for r in chosen} <= set(days)
    for trend_day in report.trend:
        that_day = [r for r in chosen if day_of(r) == trend_day.day]
        _check_period(trend_day, expected_figures(history, that_day))
        if not charted:
            assert not any(trend_day.cpk.values())
            continue
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
    whole = expected_figures(history, chosen)
    assert sum(d.units for d in report.trend) == whole.units
    assert sum(d.runs for d in report.trend) == whole.runs
    for shift in report.shift_trend:
        in_shift = [r for r in chosen if shift.start <= r.started_at < shift.end]
        _check_period(shift, expected_figures(history, in_shift))
    if report.shift_trend:
        assert sum(s.units for s in report.shift_trend) == whole.units
        assert sum(s.runs for s in report.shift_trend) == whole.runs


def _check_period(period: Any, figures: Expected) -> None:
    """A day's or a shift's runs, units and yields."""
    units = figures.units
    assert (period.runs, period.runs_passed, period.units) == (
        figures.runs,
        figures.runs_passed,
        units,
    )
    assert period.first_pass_yield == (figures.first_pass / units if units else None)
    assert period.final_yield == (figures.final_pass / units if units else None)


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
    assert _figures(what_if.summary) == expected_figures(again, chosen)
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
        chosen = {r.part_number for r in history if _selected(r, report_filter)}
        if candidate is not None and len(chosen) > 1:
            # A candidate profile is one product's: over two products it is refused.
            with pytest.raises(InputError, match="choose one"):
                eol_report(session, report_filter, candidate=candidate, zone=zone, shifts=shifts)
            candidate = None
        report = eol_report(session, report_filter, candidate=candidate, zone=zone, shifts=shifts)
        assert stored_verdicts(session) == before  # the what-if changes nothing stored
        # Over two products, capability is each product's own section's.
        parameters = report.parameters or next(
            s.parameters for s in report.product_sections if s.part_number == "DIXX-A12"
        )
        offset_x = next(p for p in parameters if p.name == "offset_x")
        assert offset_x.lower == 1841.0
        _check(report, history, report_filter)
        if candidate is not None:
            _check_what_if(report, history, report_filter)
        else:
            assert report.what_if is None
        on_hold = held_units(session, 50)
        held = {s for s, r in _latest_attempts(history).items() if not r.passed}
        assert {u.serial for u in on_hold.units} == held
        assert on_hold.total == len(held)
        kept = rollup_rows(session)
        rebuild(session.connection())
        assert rollup_rows(session) == kept
        _check(eol_report(session, report_filter, zone=zone, shifts=shifts), history, report_filter)


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


@st.composite
def unit_histories(draw: st.DrawFn) -> list[Planned]:
    """Up to 4 units of up to 4 runs each at three stations over three days: retests at
    the same station or another, aborts as a unit's first, latest or every run."""
    count = draw(st.integers(1, 4))
    serials = [f"U{i}" for i in range(count)]
    plans = {s: draw(st.integers(1, 4)) for s in serials}
    total = sum(plans.values())
    minutes = draw(
        st.lists(st.integers(0, 3 * 24 * 60), min_size=total, max_size=total, unique=True)
    )
    codes = st.sampled_from([None, "offset", "aborted"])
    runs, taken = [], iter(minutes)
    for serial in serials:
        product = draw(st.sampled_from(PRODUCTS))
        for _ in range(plans[serial]):
            code = draw(codes)
            runs.append(
                Planned(
                    serial=serial,
                    part_number=product,
                    station=draw(st.sampled_from(STATIONS)),
                    operator="op-a",
                    lot=None,
                    started_at=T0 + timedelta(minutes=next(taken)),
                    code=code,
                    charted=code is None,
                    offset_x=2048.0,
                )
            )
    return runs


windows = st.builds(
    ReportFilter,
    since=st.sampled_from(MOMENTS[:4]),
    until=st.sampled_from([None, *MOMENTS[2:]]),
    station_id=st.sampled_from([None, *STATIONS]),
)


def _yields_agree(session: Session, history: list[Planned], f: ReportFilter) -> None:
    """The summary's, each station's and each product's yields, retests and aborts equal
    the definition's; the rows add up to the line's; the units on hold are the units whose
    latest attempt failed."""
    report = eol_report(session, f, open_holds=False)
    chosen = [r for r in history if _selected(r, f)]
    _check_group(report.summary, history, chosen)
    for rows, key in ((report.stations, "station"), (report.products, "part_number")):
        by_key = {getattr(r, "station_id", None) or getattr(r, "part_number", ""): r for r in rows}
        assert sorted(by_key) == sorted({getattr(r, key) for r in chosen})
        for name, row in by_key.items():
            _check_group(row.summary, history, [r for r in chosen if getattr(r, key) == name])
        assert sum(r.summary.retests for r in rows) == report.summary.retests
        assert sum(r.summary.units_tested for r in rows) == report.summary.units_tested
    latest = _latest_attempts(history)
    on_hold = held_units(session, 50)
    held = {s for s, r in latest.items() if not r.passed}
    assert ({u.serial for u in on_hold.units}, on_hold.total) == (held, len(held))
    # The unit answers (GET /api/v1/units/{serial}) by the same definition.
    for serial in {r.serial for r in history}:
        stored = session.scalar(select(Unit.calibration).where(Unit.serial == serial))
        answer = UnitCalibration.model_validate_json(stored or "")
        assert answer.attempts == sum(_attempt(r) for r in history if r.serial == serial)
        if serial in latest:
            assert answer.verdict == ("pass" if latest[serial].passed else "fail")


@settings(
    max_examples=examples(120),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(history=unit_histories(), order=st.randoms(use_true_random=False), report_filter=windows)
def test_yields_retests_and_aborts_follow_the_one_definition(
    migrated_database: Database, history: list[Planned], order: Any, report_filter: ReportFilter
) -> None:
    """Submitted in a shuffled order, then rebuilt: the roll-ups give the definition's
    figures both ways (and the same rows)."""
    submitted = list(history)
    order.shuffle(submitted)
    with rolled_back(migrated_database) as session:
        repository = RunRepository(session)
        for run in submitted:
            repository.submit(_record(run))
        session.flush()
        _yields_agree(session, history, report_filter)
        kept = rollup_rows(session)
        rebuild(session.connection())
        assert rollup_rows(session) == kept
        _yields_agree(session, history, report_filter)


def _run(serial: str, station: str, day: int, hour: int, code: str | None) -> Planned:
    return Planned(
        serial=serial,
        part_number=PRODUCTS[0],
        station=station,
        operator="op-a",
        lot=None,
        started_at=DAY0 + timedelta(days=day, hours=hour),
        code=code,
        charted=code is None,
        offset_x=2048.0,
    )


#: Day 0: U1 aborted at st1, then passed at st2; U2 failed at st1, passed at st2; U3
#: failed at st1, retested there on day 1 (failed), then passed at st3 on day 1; U4 only
#: aborted. Day 1: U5 passed at st3 first time.
ISSUE_42 = [
    _run("U1", "st1", 0, 8, "aborted"),
    _run("U1", "st2", 0, 9, None),
    _run("U2", "st1", 0, 10, "offset"),
    _run("U2", "st2", 0, 11, None),
    _run("U3", "st1", 0, 12, "offset"),
    _run("U4", "st1", 0, 13, "aborted"),
    _run("U3", "st1", 1, 8, "offset"),
    _run("U3", "st3", 1, 9, None),
    _run("U5", "st3", 1, 10, None),
]


@pytest.mark.parametrize(
    ("since", "line", "stations"),
    [
        # (units, first passes, final passes, retests, aborts) of the line and per station
        (
            None,
            (4, 2, 4, 3, 2),
            {"st1": (2, 0, 2, 1, 2), "st2": (1, 1, 1, 1, 0), "st3": (1, 1, 1, 1, 0)},
        ),
        # Day 1 alone holds only U3's later attempts: retests, and no unit of the day's.
        (
            DAY0 + timedelta(days=1),
            (1, 1, 1, 2, 0),
            {"st1": (0, 0, 0, 1, 0), "st3": (1, 1, 1, 1, 0)},
        ),
    ],
)
def test_a_first_run_aborted_and_retests_elsewhere_count_where_each_attempt_ran(
    session: Session,
    since: datetime | None,
    line: tuple[int, ...],
    stations: dict[str, tuple[int, ...]],
) -> None:
    """U1's aborted first run is no attempt, so its pass at st2 is its first
    (first-pass, no retest); each retest is its own station's, never another's cohort;
    U4, aborted only, is no unit; a window holding only later attempts counts retests."""
    repository = RunRepository(session)
    for run in reversed(ISSUE_42):
        repository.submit(_record(run))
    session.flush()

    def five(summary: Any) -> tuple[int, ...]:
        return (
            summary.units_tested,
            summary.first_pass_units,
            summary.units_passed,
            summary.retests,
            summary.aborted_runs,
        )

    report = eol_report(session, ReportFilter(since=since))
    assert five(report.summary) == line
    assert {s.station_id: five(s.summary) for s in report.stations} == stations
    assert held_units(session, 10).total == 0  # U4 was never attempted: not on hold
