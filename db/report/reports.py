"""The end-of-line report assembled from the rows of :mod:`db.report.queries`.

The control-chart limits add up the stored moving ranges; the control-chart points
walk ``ix_runs_started_at`` backwards. Python only merges the grouped rows (stations,
profiles: a few dozen) and applies the capability formulas of
:mod:`station.domain.quality.capability`.
"""

from collections import defaultdict
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from datetime import UTC, datetime, time
from itertools import groupby
from operator import attrgetter
from typing import Any

from sqlalchemy import Row, RowMapping
from sqlalchemy.orm import Session

from db.report.chart_queries import (
    chart_limits,
    first_moving_ranges,
    latest_chart_points,
    latest_values,
)
from db.report.queries import DIMENSIONS, ReportQueries
from db.report.trends import moments, ratio, report_trend
from db.report.what_if import rejudged
from db.rollups import HISTOGRAM, stored_bounds
from db.store.limits_profiles import stored_profiles
from station.domain.errors import InputError
from station.domain.product.limits import LimitsProfile
from station.domain.quality.capability import (
    D2,
    capability_warning,
    cp,
    cpk,
    data_bins,
    histogram_bins,
    individuals_limits,
    observed_ppm,
)
from station.domain.quality.control import moving_range_sigma, western_electric
from station.domain.quality.figures import (
    ChartPoint,
    ControlChart,
    Distribution,
    EolReport,
    Histogram,
    NearLimits,
    ParameterStats,
    ParetoEntry,
    ProductSection,
    ProductSummary,
    ReportFilter,
    StationSummary,
    Summary,
    UnitVerdict,
    WhatIf,
)
from station.domain.quality.parameters import (
    COEFFICIENTS,
    PARAMETERS,
    FamilyBounds,
    ParameterSpec,
    profile_bounds,
)
from station.domain.quality.shifts import shift_name
from station.domain.record.records import LimitsRef
from station.domain.record.unit_state import ABORTED

#: Points drawn on each control chart (the latest runs); its limits use every run.
CHART_POINTS = 200
#: The latest runs in range whose values the histograms draw (bins from the data).
HISTOGRAM_RUNS = 1000


# -- assembling the report -------------------------------------------------------------


@dataclass(frozen=True)
class _Counts:
    """What a summary is computed from (one station, or the line), by the yield
    definition of :mod:`db.rollups`: ``units`` whose first attempt is among the runs,
    ``first_pass`` / ``final_pass`` of them whose first / latest attempt passed,
    ``retests`` the attempts that are not their unit's first, ``aborted`` the runs the
    operator aborted (no attempts)."""

    runs: int
    runs_passed: int
    units: int
    first_pass: int
    final_pass: int
    retests: int
    aborted: int
    seconds: float | None
    poses: int


def _total(rows: Sequence[Row[Any]], column: str) -> int:
    return sum(int(row._mapping[column]) for row in rows)


def _counts(rows: Sequence[Row[Any]]) -> _Counts:
    """The counts of ``rows`` of :meth:`ReportQueries.station_counts` (or of
    :meth:`ReportQueries.product_counts`): a unit counts where its first attempt on the
    line is and a retest where it ran, so a station's units are those whose first
    attempt was there, its retests its own, and the stations' rows add up to the
    line's."""
    return _Counts(
        runs=_total(rows, "runs"),
        runs_passed=_total(rows, "runs_passed"),
        units=_total(rows, "line_units"),
        first_pass=_total(rows, "line_first_pass"),
        final_pass=_total(rows, "line_final_pass"),
        retests=_total(rows, "retests"),
        aborted=_total(rows, "aborts"),
        seconds=_total(rows, "duration_ms") / 1000 if rows else None,
        poses=_total(rows, "poses"),
    )


def _summary(n: _Counts, hours: float | None) -> Summary:
    return Summary(
        aborted_runs=n.aborted,
        runs=n.runs,
        runs_passed=n.runs_passed,
        units_tested=n.units,
        units_passed=n.final_pass,
        units_failed=n.units - n.final_pass,
        first_pass_units=n.first_pass,
        report_yield=ratio(n.runs_passed, n.runs),
        first_pass_yield=ratio(n.first_pass, n.units),
        final_yield=ratio(n.final_pass, n.units),
        retests=n.retests,
        retest_rate=ratio(n.retests, n.units),
        hours=hours,
        units_per_hour=units_per_hour(n.units, n.seconds),
        cycle_time_per_run_s=ratio(n.seconds, n.runs) if n.seconds is not None else None,
        cycle_time_per_unit_s=ratio(n.seconds, n.units) if n.seconds is not None else None,
        cycle_time_per_pose_s=ratio(n.seconds, n.poses) if n.seconds is not None else None,
        poses=n.poses,
    )


def units_per_hour(units: int, station_seconds: float | None) -> float | None:
    """Units per hour of station time (``station_seconds``, Σ finish − start of the
    runs): 3600 / seconds per unit, on the same basis as the cycle times beside it, the
    same for any page over the same runs (the dashboard's, the report's)."""
    return ratio(3600 * units, station_seconds) if station_seconds else None


def _hours(filter: ReportFilter, rows: Sequence[Row[Any]]) -> float | None:
    start = filter.since or min((r.first_start for r in rows), default=None)
    end = filter.until or max((r.last_finish for r in rows), default=None)
    if start is None or end is None or end <= start:
        return None
    return float((end - start).total_seconds() / 3600)


def _products(queries: ReportQueries, hours: float | None) -> list[ProductSummary]:
    """Each product's summary: a unit is one product's, so the rows add up to the
    line's as the stations' do. Each one's row of :meth:`ReportQueries.product_counts`."""
    return [
        ProductSummary(part_number=row.part_number, summary=_summary(_counts([row]), hours))
        for row in queries.product_counts()
    ]


def _pareto(rows: Iterable[Sequence[Any]]) -> list[ParetoEntry]:
    """Failing runs by first failure reason, from ``rows`` of (first failure reason,
    station, operator, failing runs); an operator's abort is no failure of the unit and no
    category here (the summary counts aborts apart)."""
    counts: dict[str, int] = defaultdict(int)
    stations: dict[str, dict[str, int]] = defaultdict(lambda: defaultdict(int))
    operators: dict[str, dict[str, int]] = defaultdict(lambda: defaultdict(int))
    for code, station, operator, runs in rows:
        if code == ABORTED:
            continue
        n = int(runs)
        counts[code] += n
        stations[code][station] += n
        operators[code][operator] += n
    total, cumulative, entries = sum(counts.values()), 0, []
    for code, n in sorted(counts.items(), key=lambda item: (-item[1], item[0])):
        cumulative += n
        entries.append(
            ParetoEntry(
                code=code,
                count=n,
                share=n / total,
                cumulative_share=cumulative / total,
                by_station=dict(sorted(stations[code].items())),
                by_operator=dict(sorted(operators[code].items())),
            )
        )
    return entries


def _parameter(spec: ParameterSpec, bounds: FamilyBounds, row: RowMapping | None) -> ParameterStats:
    """One parameter's statistics from its row of :meth:`ReportQueries.parameters`."""
    lower, upper = bounds[spec.family]
    start, width, _ = histogram_bins(lower, upper)
    count = 0 if row is None else int(row["n"])
    mean, std = moments(row, lower, upper) if row is not None and count else (None, None)
    out = 0 if row is None else int(row["outside"])
    capability = cpk(mean, std, lower, upper)
    return ParameterStats(
        name=spec.name,
        family=spec.family,
        unit=spec.unit,
        lower=lower,
        upper=upper,
        count=count,
        mean=mean,
        std=std,
        min=None if row is None else float(row["min"]),
        max=None if row is None else float(row["max"]),
        cp=cp(std, lower, upper),
        cpk=capability,
        out_of_limits=out,
        observed_ppm=observed_ppm(out, count),
        warning=capability_warning(capability, out, count),
        marginal=0 if row is None else int(row["marginal"]),
        histogram=Histogram(
            start=start,
            width=width,
            counts=[0 if row is None else int(row[h]) for h in HISTOGRAM],
        ),
    )


def _distribution(values: Sequence[float], runs: int) -> Distribution | None:
    """The histogram of ``values`` (of the latest ``runs`` runs) in bins from the data."""
    if not values:
        return None
    edges, counts, below, above = data_bins(values)
    return Distribution(
        edges=edges,
        counts=counts,
        values=len(values),
        below=below,
        above=above,
        mean=sum(values) / len(values),
        runs=runs,
    )


@dataclass(frozen=True)
class _ChartLimits:
    """What the control charts' limits are computed from: runs with coefficients, and
    per coefficient its mean and mean moving range (``None``: fewer than two runs)."""

    count: int
    means: Mapping[str, float | None]
    mr_bars: Mapping[str, float | None]


def _chart_limits(
    queries: ReportQueries, counts: Sequence[Row[Any]], stats: Mapping[str, ParameterStats]
) -> _ChartLimits:
    """The control-chart limits of the runs in range, in their time order.

    A range narrowed only in time holds consecutive runs of the line: their moving
    ranges are the stored ones (each run's to the line's previous run with
    coefficients) but the first run's, whose previous run lies before the range. Runs
    narrowed by station, operator or lot, or reported without limits (no statistics),
    are ordered and differenced in SQL.
    """
    narrowed = any(getattr(queries.filter, name) is not None for name in DIMENSIONS)
    if narrowed or not all(name in stats for name in COEFFICIENTS):
        row = chart_limits(queries.session, queries.conditions)._mapping
        return _ChartLimits(
            count=int(row["n"]),
            means={name: row[name] for name in COEFFICIENTS},
            mr_bars={name: row[f"mr_{name}"] for name in COEFFICIENTS},
        )
    n = _total(counts, "charted")
    first = first_moving_ranges(queries.session, queries.conditions) if n > 1 else None
    mr_bars: dict[str, float | None] = {}
    for name in COEFFICIENTS:
        total = sum(float(row._mapping[f"mr_{name}"]) for row in counts)
        before = None if first is None else first._mapping[name]
        mr_bars[name] = (total - (before or 0.0)) / (n - 1) if n > 1 else None
    return _ChartLimits(
        count=n, means={name: stats[name].mean for name in COEFFICIENTS}, mr_bars=mr_bars
    )


def _charts(limits: _ChartLimits, points: Sequence[Row[Any]]) -> list[ControlChart]:
    charts = []
    units = {spec.name: spec.unit for spec in PARAMETERS}
    for name in COEFFICIENTS:
        mean, mr_bar = limits.means[name], limits.mr_bars[name]
        if mean is None or not limits.count:
            continue
        lcl = ucl = mr_ucl = sigma = mr_sigma = None
        values = [float(getattr(p, name)) for p in points]
        ranges = [getattr(p, f"mr_{name}") for p in points]
        signals: list[list[int]] = [[] for _ in points]
        mr_signals: list[list[int]] = [[] for _ in points]
        if mr_bar is not None:
            lcl, ucl, mr_ucl = individuals_limits(float(mean), float(mr_bar))
            sigma, mr_sigma = float(mr_bar) / D2, moving_range_sigma(float(mr_bar))
            signals = western_electric(values, float(mean), sigma)
            # The first point's moving range may reach before the plotted points.
            plotted = [r for r in ranges if r is not None]
            flags = iter(western_electric(plotted, float(mr_bar), mr_sigma))
            mr_signals = [[] if r is None else next(flags) for r in ranges]
        charts.append(
            ControlChart(
                name=name,
                unit=units[name],
                count=limits.count,
                mean=float(mean),
                mr_bar=None if mr_bar is None else float(mr_bar),
                lcl=lcl,
                ucl=ucl,
                mr_ucl=mr_ucl,
                sigma=sigma,
                mr_sigma=mr_sigma,
                points=[
                    ChartPoint(
                        started_at=p.started_at,
                        serial=p.serial,
                        value=value,
                        moving_range=moving_range,
                        signals=signal,
                        mr_signals=mr_signal,
                    )
                    for p, value, moving_range, signal, mr_signal in zip(
                        points, values, ranges, signals, mr_signals, strict=True
                    )
                ],
            )
        )
    return charts


def report_bounds(session: Session, counts: Sequence[Row[Any]]) -> tuple[FamilyBounds | None, str]:
    """The bounds capability is measured against, and a line saying which and why.

    The stored profile (:mod:`db.store.limits_profiles`) of the latest run in range (by
    finish), or of the latest whose profile is stored; with none stored (runs from
    stations older than stored profiles, or no run in range), the bounds the roll-ups
    were counted with; with none of those either, ``None``: no capability.
    """
    finished: dict[LimitsRef, datetime] = {}
    for row in counts:
        ref = LimitsRef(name=row.limits_name, version=row.limits_version, sha256=row.limits_sha256)
        finished[ref] = max(row.last_finish, finished.get(ref, row.last_finish))
    latest_first = sorted(finished, key=lambda ref: finished[ref], reverse=True)
    stored = stored_profiles(session, {ref.sha256 for ref in latest_first})
    for ref in latest_first:
        if ref.sha256 in stored:
            if len(latest_first) == 1:
                why = "every run in range"
            elif ref == latest_first[0]:
                why = f"the latest run's, of {len(latest_first)} profiles in range"
            else:
                why = "the latest run's whose profile is stored"
            named = f"{ref.name} v{ref.version} ({ref.sha256[:12]})"
            return profile_bounds(stored[ref.sha256]), f"limits profile {named} ({why})"
    binned = stored_bounds(session.connection())
    missing = "no run in range" if not latest_first else "no profile of the runs in range stored"
    if binned:
        return binned, f"the bounds the roll-ups were counted with ({missing})"
    return None, f"no limits ({missing}): no capability"


def _capability(queries: ReportQueries, bounds: FamilyBounds) -> tuple[list[ParameterStats], bool]:
    """Every parameter's statistics against ``bounds``, and whether the roll-ups answered."""
    rows, rolled = queries.parameters(bounds)
    return [_parameter(spec, bounds, rows.get(spec.name)) for spec in PARAMETERS], rolled


def _what_if(
    queries: ReportQueries,
    candidate: LimitsProfile,
    current: _Counts,
    hours: float | None,
    kept: bool,
) -> WhatIf:
    """The runs in range re-judged against ``candidate``: yields, Pareto, capability;
    ``kept``: the candidate is stored (its link answers it again).

    A candidate judges attempts again and leaves aborts aborts: the attempts, so the
    units, retests and aborts, are the report's (``current``)."""
    judged = rejudged(queries.session, queries.conditions, candidate)
    counts = replace(
        current,
        runs=judged.runs,
        runs_passed=judged.runs_passed,
        units=judged.units,
        first_pass=judged.first_pass,
        final_pass=judged.final_pass,
    )
    parameters, _ = _capability(queries, profile_bounds(candidate))
    return WhatIf(
        limits=candidate.ref,
        summary=_summary(counts, hours),
        pareto=_pareto((*key, n) for key, n in judged.failures.items()),
        parameters=parameters,
        pass_to_fail=judged.pass_to_fail,
        fail_to_pass=judged.fail_to_pass,
        flips=judged.flips,
        flips_total=judged.flips_total,
        kept=kept,
    )


def _profiles_used(counts: Sequence[Row[Any]]) -> list[LimitsRef]:
    """The limits profiles the runs of ``counts`` (:meth:`ReportQueries.station_counts`)
    were judged by."""
    refs = sorted({(r.limits_name, r.limits_version, r.limits_sha256) for r in counts})
    return [LimitsRef(name=name, version=version, sha256=sha) for name, version, sha in refs]


@dataclass(frozen=True)
class _Statistics:
    """The statistics of coefficients of one product's runs (none: runs of several
    products, which no statistic spans): the ``bounds`` they are judged against and
    where they come from, capability, control charts and near-limit runs."""

    bounds: FamilyBounds | None = None
    source: str = ""
    parameters: list[ParameterStats] = field(default_factory=list)
    charts: list[ControlChart] = field(default_factory=list)
    near_limits: NearLimits | None = None


def _statistics(queries: ReportQueries, counts: Sequence[Row[Any]], points: int) -> _Statistics:
    """The statistics of the runs ``queries`` select (of one product), ``counts`` their
    :meth:`ReportQueries.station_counts`, against the profile :func:`report_bounds`
    picks; ``points`` on each control chart."""
    session = queries.session
    bounds, source = report_bounds(session, counts)
    parameters: list[ParameterStats] = []
    if bounds is not None:
        parameters, rolled = _capability(queries, bounds)
        if not rolled:
            source += "; statistics from the runs, not the roll-ups' other bounds"
    values: dict[str, list[float]] = {}
    if parameters:
        values, sampled = latest_values(session, queries.conditions, HISTOGRAM_RUNS)
        parameters = [
            p.model_copy(update={"distribution": _distribution(values[p.name], sampled)})
            for p in parameters
        ]
    limits = _chart_limits(queries, counts, {p.name: p for p in parameters})
    return _Statistics(
        bounds=bounds,
        source=source,
        parameters=parameters,
        charts=_charts(limits, latest_chart_points(session, queries.conditions, points)),
        near_limits=None if bounds is None else queries.near_limits(bounds, parameters, values),
    )


def _section(
    session: Session,
    filter: ReportFilter,
    part_number: str,
    points: int,
    zone: str,
    shifts: Sequence[time],
) -> ProductSection:
    """One product's section of a report over several: ``filter`` narrowed to
    ``part_number``."""
    filter = filter.model_copy(update={"part_number": part_number})
    queries = ReportQueries(session, filter)
    counts = queries.station_counts()
    stats = _statistics(queries, counts, points)
    trend, shift_trend = report_trend(session, filter, counts, stats.bounds, zone, shifts)
    return ProductSection(
        part_number=part_number,
        filter=filter,
        bounds_source=stats.source,
        limits_profiles=_profiles_used(counts),
        parameters=stats.parameters,
        control_charts=stats.charts,
        near_limits=stats.near_limits,
        trend=trend,
        shift_trend=shift_trend,
    )


def eol_report(
    session: Session,
    filter: ReportFilter,
    *,
    candidate: LimitsProfile | None = None,
    unit_limit: int | None = None,
    chart_points: int = CHART_POINTS,
    now: datetime | None = None,
    zone: str = "UTC",
    held_only: bool = False,
    unit_offset: int = 0,
    shifts: Sequence[time] = (),
    open_holds: bool = True,
    candidate_kept: bool = False,
) -> EolReport:
    """The end-of-line report over the runs ``filter`` selects.

    Capability is measured against the stored profile :func:`report_bounds` picks for
    the runs in range. Runs of several products get no such statistic over them all:
    each product gets a section of its own (:class:`ProductSection`), its runs against
    its own profile; counts and yields stay the line's, with a row per product. A
    ``candidate`` profile adds the what-if: the runs re-judged against it
    (:mod:`db.report.what_if`), nothing stored changed; a profile is one product's, so
    runs of several products refuse it (:class:`InputError`). ``unit_limit`` cuts the
    unit list to the latest units. ``zone`` is the plant's time zone: the trend's days
    are its days; ``shifts`` its shifts' start times, for a trend per shift too.
    ``held_only`` lists only the held units (latest attempt failed), ``unit_offset``
    skips the newest (pages); ``open_holds``: count the open holds too;
    ``candidate_kept``: the candidate is stored.
    """
    queries = ReportQueries(session, filter)
    counts = queries.station_counts()
    hours = _hours(filter, counts)
    units = [
        UnitVerdict(
            serial=row.serial,
            disposition="ship" if row.shipped else "hold",
            verdict=row.verdict,
            runs=row.runs,
            last_started_at=row.started_at,
            station_id=row.station_id,
            operator_id=row.operator_id,
            failure=row.code,
        )
        for row in queries.latest_runs(unit_limit, unit_offset, held_only)
    ]
    line = _counts(counts)
    products = _products(queries, hours)
    several = [p.part_number for p in products] if len(products) > 1 else []
    if candidate is not None and several:
        raise InputError(
            f"a what-if's candidate limits profile is one product's, and the runs selected are "
            f"of {len(several)} products ({', '.join(several)}): choose one (part_number)"
        )
    stats = _Statistics() if several else _statistics(queries, counts, chart_points)
    what_if = (
        None if candidate is None else _what_if(queries, candidate, line, hours, candidate_kept)
    )
    trend, shift_trend = report_trend(session, filter, counts, stats.bounds, zone, shifts)
    sections = [_section(session, filter, part, chart_points, zone, shifts) for part in several]
    generated_at = now or datetime.now(UTC)
    return EolReport(
        generated_at=generated_at,
        filter=filter,
        bounds_source=(
            f"each product against its own limits profile ({len(several)} products in range)"
            if several
            else stats.source
        ),
        limits_profiles=_profiles_used(counts),
        summary=_summary(line, hours),
        stations=[  # counts are sorted by station
            StationSummary(station_id=station, summary=_summary(_counts(list(rows)), hours))
            for station, rows in groupby(counts, attrgetter("station_id"))
        ],
        products=products,
        timezone=zone,
        trend=trend,
        shifts=[shift_name(at) for at in shifts],
        shift_trend=shift_trend,
        pareto=_pareto(queries.first_failures()),
        parameters=stats.parameters,
        control_charts=stats.charts,
        units=units,
        units_total=line.units,
        units_held=line.units - line.final_pass,
        units_listed="held" if held_only else "all",
        units_offset=unit_offset,
        units_limit=unit_limit,
        what_if=what_if,
        near_limits=stats.near_limits,
        open_holds=queries.open_holds(generated_at) if open_holds else None,
        product_sections=sections,
    )
