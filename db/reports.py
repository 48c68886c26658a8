"""Aggregation queries of the end-of-line report, one SQL statement per section.

Nothing here walks runs in Python: counts and yields come from one grouped query over a
window (``row_number``/``lead`` per unit, ordered by start time), the Pareto from the
first failure reason of each failing run grouped by code, station and operator, the
parameter statistics and histograms from one grouped query per table (each parameter
an unpivoted row, grouped by parameter and bin), the control-chart limits from ``lag``
over the runs in time order. Python only combines the grouped rows (a few hundred) and
applies the capability formulas of :mod:`station.report.capability`.
"""

from collections import defaultdict
from collections.abc import Mapping, Sequence
from datetime import UTC, datetime
from typing import Any

from sqlalchemy import (
    ColumnElement,
    Float,
    Integer,
    Row,
    String,
    Subquery,
    and_,
    case,
    cast,
    extract,
    func,
    literal,
    select,
    true,
    type_coerce,
    union_all,
)
from sqlalchemy.orm import Session

from db.models import Pose, Run, RunFailure
from station.limits import LimitsProfile, load_profiles
from station.records import LimitsRef
from station.report.bounds import (
    COEFFICIENTS,
    PARAMETERS,
    Bounds,
    ParameterSpec,
    choose_profile,
    profile_bounds,
)
from station.report.capability import (
    cp,
    cpk,
    histogram_bins,
    individuals_limits,
    marginal_zones,
    shifted_moments,
    tolerance,
)
from station.report.model import (
    ChartPoint,
    ControlChart,
    EolReport,
    Histogram,
    ParameterStats,
    ParetoEntry,
    ReportFilter,
    StationSummary,
    Summary,
    UnitVerdict,
)

#: Stands for a missing limit inside SQL (no stored value comes near it).
NO_LIMIT = 1e300
#: Points drawn on each control chart (the latest runs); its limits use every run.
CHART_POINTS = 200


class ReportQueries:
    """The report's queries over the runs ``filter`` selects, in the caller's session."""

    def __init__(self, session: Session, filter: ReportFilter) -> None:
        self.session = session
        self.filter = filter
        self.dialect = session.get_bind().dialect.name

    # -- helpers -----------------------------------------------------------------------

    def conditions(self) -> list[ColumnElement[bool]]:
        """The ``WHERE`` clauses on ``runs`` of the filter."""
        f, where = self.filter, []
        if f.since is not None:
            where.append(Run.started_at >= f.since)
        if f.until is not None:
            where.append(Run.started_at < f.until)
        if f.station_id is not None:
            where.append(Run.station_id == f.station_id)
        if f.operator_id is not None:
            where.append(Run.operator_id == f.operator_id)
        return where

    def _seconds(self) -> ColumnElement[float]:
        """A run's duration in seconds."""
        if self.dialect == "postgresql":
            return type_coerce(extract("epoch", Run.finished_at - Run.started_at), Float)
        # julianday() carries about 10 µs; round to the millisecond.
        days = func.julianday(Run.finished_at) - func.julianday(Run.started_at)
        return func.round(days * 86400.0, 3)

    # -- counts and yields -------------------------------------------------------------

    def summaries(self, *, by_station: bool) -> list[Row[Any]]:
        """Counts per station (or overall): runs, passes, units, first and final passes.

        Each run is ranked within its unit (and station) by ``(started_at, id)``: rank 1
        is the unit's first run, a run without a ``lead`` its latest.
        """
        partition = [Run.station_id, Run.serial] if by_station else [Run.serial]
        order = (Run.started_at, Run.id)
        ranked = (
            select(
                Run.station_id,
                Run.verdict,
                Run.started_at,
                Run.finished_at,
                self._seconds().label("seconds"),
                func.row_number().over(partition_by=partition, order_by=order).label("nth"),
                func.lead(Run.id).over(partition_by=partition, order_by=order).label("next_id"),
            )
            .where(*self.conditions())
            .subquery("ranked")
        )
        passed = ranked.c.verdict == "pass"
        first, last = ranked.c.nth == 1, ranked.c.next_id.is_(None)

        def count_if(condition: ColumnElement[bool]) -> ColumnElement[int]:
            return func.coalesce(func.sum(case((condition, 1), else_=0)), 0)

        columns = [
            func.count().label("runs"),
            count_if(passed).label("runs_passed"),
            count_if(first).label("units"),
            count_if(and_(first, passed)).label("first_pass"),
            count_if(and_(last, passed)).label("final_pass"),
            func.sum(ranked.c.seconds).label("seconds"),
            func.min(ranked.c.started_at).label("first_start"),
            func.max(ranked.c.finished_at).label("last_finish"),
        ]
        if by_station:
            stmt = (
                select(ranked.c.station_id, *columns)
                .group_by(ranked.c.station_id)
                .order_by(ranked.c.station_id)
            )
        else:
            stmt = select(*columns)
        return list(self.session.execute(stmt).all())

    def pose_counts(self) -> dict[str, int]:
        """Poses per station."""
        stmt = (
            select(Run.station_id, func.count())
            .select_from(Pose)
            .join(Run, Pose.run_pk == Run.id)
            .where(*self.conditions())
            .group_by(Run.station_id)
        )
        return {station: count for station, count in self.session.execute(stmt)}

    # -- failures ----------------------------------------------------------------------

    def first_failures(self) -> list[Row[str, str, str, int]]:
        """Failing runs per (first failure code, station, operator)."""
        stmt = (
            select(RunFailure.code, Run.station_id, Run.operator_id, func.count().label("n"))
            .join(Run, RunFailure.run_pk == Run.id)
            .where(RunFailure.position == 0, Run.verdict == "fail", *self.conditions())
            .group_by(RunFailure.code, Run.station_id, Run.operator_id)
        )
        return list(self.session.execute(stmt).all())

    # -- parameters --------------------------------------------------------------------

    def _value(self, spec: ParameterSpec) -> ColumnElement[float]:
        if spec.source == "poses":
            column: ColumnElement[float] = getattr(Pose, spec.column)
            return column
        if spec.family == "gyro_bias":
            bias: ColumnElement[float] = Run.gyro[("bias", spec.column)].as_float()
            return bias
        run_column: ColumnElement[float] = getattr(Run, spec.column)
        return run_column

    @staticmethod
    def _parameter_table(specs: Sequence[ParameterSpec], bounds: Bounds) -> Subquery:
        """One row per parameter: its name, summing shift, bins and limits (SQL literals)."""
        rows = []
        for spec in specs:
            lower, upper = bounds[spec.family]
            start, width, bins = histogram_bins(lower, upper)
            zone_low, zone_high = marginal_zones(lower, upper)
            low, high = tolerance(lower, upper)
            numbers = {
                "shift": (low + high) / 2,
                "start": start,
                "width": width,
                "lower": -NO_LIMIT if lower is None else lower,
                "upper": NO_LIMIT if upper is None else upper,
                "zone_low": -NO_LIMIT if lower is None else zone_low,
                "zone_high": NO_LIMIT if upper is None else zone_high,
            }
            rows.append(
                select(
                    cast(literal(spec.name), String).label("name"),
                    cast(literal(bins), Integer).label("bins"),
                    *(cast(literal(v), Float).label(k) for k, v in numbers.items()),
                )
            )
        return union_all(*rows).subquery("p")

    def parameter_bins(self, source: str, bounds: Bounds) -> list[Row[Any]]:
        """Per parameter of ``source`` and histogram bin: count, shifted sums, min, max,
        values out of limits and marginal values.

        The table is scanned once: each row is crossed with the parameter list and the
        ``CASE`` picks that parameter's value (an unpivot that both dialects run).
        """
        specs = [spec for spec in PARAMETERS if spec.source == source]
        p = self._parameter_table(specs, bounds)
        value = case(*((p.c.name == spec.name, self._value(spec)) for spec in specs))
        base = select(p, value.label("value"))
        if source == "poses":
            base = base.select_from(Pose).join(Run, Pose.run_pk == Run.id)
        else:
            base = base.select_from(Run)
        v = base.join(p, true()).where(*self.conditions()).subquery("v")
        top = v.c.bins - 1
        bin_ = case(
            (v.c.value < v.c.start, 0),
            (v.c.value >= v.c.start + v.c.width * v.c.bins, top),
            else_=cast(func.floor((v.c.value - v.c.start) / v.c.width), Integer),
        )
        deviation = v.c.value - v.c.shift
        outside = (v.c.value < v.c.lower) | (v.c.value > v.c.upper)
        marginal = and_(~outside, (v.c.value < v.c.zone_low) | (v.c.value > v.c.zone_high))
        stmt = (
            select(
                v.c.name,
                bin_.label("bin"),
                func.count().label("n"),
                func.sum(deviation).label("sum"),
                func.sum(deviation * deviation).label("squares"),
                func.min(v.c.value).label("min"),
                func.max(v.c.value).label("max"),
                func.sum(case((outside, 1), else_=0)).label("outside"),
                func.sum(case((marginal, 1), else_=0)).label("marginal"),
            )
            .where(v.c.value.is_not(None))
            .group_by(v.c.name, bin_)
        )
        return list(self.session.execute(stmt).all())

    # -- control charts ----------------------------------------------------------------

    def chart_limits(self) -> Row[Any]:
        """Count, mean and mean moving range of every coefficient, in time order."""
        order = (Run.started_at, Run.id)
        columns = [getattr(Run, name) for name in COEFFICIENTS]
        lagged = (
            select(
                *columns,
                *(
                    func.abs(c - func.lag(c).over(order_by=order)).label(f"mr_{c.key}")
                    for c in columns
                ),
            )
            .where(Run.offset_x.is_not(None), *self.conditions())
            .subquery("lagged")
        )
        return self.session.execute(
            select(
                func.count().label("n"),
                *(func.avg(lagged.c[name]).label(name) for name in COEFFICIENTS),
                *(func.avg(lagged.c[f"mr_{name}"]).label(f"mr_{name}") for name in COEFFICIENTS),
            )
        ).one()

    def chart_points(self, limit: int) -> list[Row[Any]]:
        """The latest ``limit`` runs with coefficients, oldest first, with moving ranges."""
        latest = (
            select(Run.id, Run.started_at, Run.serial, *(getattr(Run, n) for n in COEFFICIENTS))
            .where(Run.offset_x.is_not(None), *self.conditions())
            .order_by(Run.started_at.desc(), Run.id.desc())
            .limit(limit + 1)
            .subquery("latest")
        )
        order = (latest.c.started_at, latest.c.id)
        inner = select(
            latest,
            func.row_number().over(order_by=order).label("nth"),
            *(
                func.abs(latest.c[n] - func.lag(latest.c[n]).over(order_by=order)).label(f"mr_{n}")
                for n in COEFFICIENTS
            ),
        ).subquery("charted")
        count = select(func.count()).select_from(latest).scalar_subquery()
        stmt = (
            select(inner)
            .where((inner.c.nth > 1) | (count <= limit))
            .order_by(inner.c.started_at, inner.c.id)
        )
        return list(self.session.execute(stmt).all())

    # -- units -------------------------------------------------------------------------

    def latest_runs(self, limit: int | None) -> list[Row[Any]]:
        """Each unit's latest run with its run count and first failure code, newest first."""
        ranked = (
            select(
                Run.id,
                Run.serial,
                Run.verdict,
                Run.started_at,
                Run.station_id,
                Run.operator_id,
                func.row_number()
                .over(partition_by=Run.serial, order_by=(Run.started_at.desc(), Run.id.desc()))
                .label("nth"),
                func.count().over(partition_by=Run.serial).label("runs"),
            )
            .where(*self.conditions())
            .subquery("ranked")
        )
        stmt = (
            select(ranked, RunFailure.code)
            .outerjoin(RunFailure, and_(RunFailure.run_pk == ranked.c.id, RunFailure.position == 0))
            .where(ranked.c.nth == 1)
            .order_by(ranked.c.started_at.desc(), ranked.c.id.desc())
            .limit(limit)
        )
        return list(self.session.execute(stmt).all())

    def limits_profiles(self) -> list[LimitsRef]:
        """The limits profiles the runs in range were judged by."""
        stmt = (
            select(Run.limits_name, Run.limits_version, Run.limits_sha256)
            .where(*self.conditions())
            .distinct()
            .order_by(Run.limits_name, Run.limits_version, Run.limits_sha256)
        )
        return [
            LimitsRef(name=name, version=version, sha256=sha)
            for name, version, sha in self.session.execute(stmt)
        ]


# -- assembling the report -------------------------------------------------------------


def _ratio(part: float, whole: float) -> float | None:
    return part / whole if whole else None


def _summary(row: Row[Any], poses: int, hours: float | None) -> Summary:
    runs, units = int(row.runs), int(row.units)
    seconds = float(row.seconds) if row.seconds is not None else None
    retests = runs - units
    return Summary(
        runs=runs,
        runs_passed=int(row.runs_passed),
        units_tested=units,
        units_passed=int(row.final_pass),
        units_failed=units - int(row.final_pass),
        first_pass_units=int(row.first_pass),
        report_yield=_ratio(row.runs_passed, runs),
        first_pass_yield=_ratio(row.first_pass, units),
        final_yield=_ratio(row.final_pass, units),
        retests=retests,
        retest_rate=_ratio(retests, units),
        hours=hours,
        units_per_hour=_ratio(units, hours) if hours else None,
        cycle_time_per_run_s=_ratio(seconds, runs) if seconds is not None else None,
        cycle_time_per_unit_s=_ratio(seconds, units) if seconds is not None else None,
        cycle_time_per_pose_s=_ratio(seconds, poses) if seconds is not None else None,
        poses=poses,
    )


def _hours(filter: ReportFilter, row: Row[Any]) -> float | None:
    start = filter.since or row.first_start
    end = filter.until or row.last_finish
    if start is None or end is None or end <= start:
        return None
    return float((end - start).total_seconds() / 3600)


def _pareto(rows: Sequence[Row[str, str, str, int]]) -> list[ParetoEntry]:
    counts: dict[str, int] = defaultdict(int)
    stations: dict[str, dict[str, int]] = defaultdict(lambda: defaultdict(int))
    operators: dict[str, dict[str, int]] = defaultdict(lambda: defaultdict(int))
    for code, station, operator, n in rows:
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


def _parameter(spec: ParameterSpec, bounds: Bounds, bins: Sequence[Row[Any]]) -> ParameterStats:
    lower, upper = bounds[spec.family]
    start, width, n_bins = histogram_bins(lower, upper)
    low, high = tolerance(lower, upper)
    counts = [0] * n_bins
    for row in bins:
        counts[row.bin] = int(row.n)
    count = sum(counts)
    mean, std = shifted_moments(
        count,
        sum(float(r.sum) for r in bins),
        sum(float(r.squares) for r in bins),
        (low + high) / 2,
    )
    return ParameterStats(
        name=spec.name,
        family=spec.family,
        unit=spec.unit,
        lower=lower,
        upper=upper,
        count=count,
        mean=mean,
        std=std,
        min=min((float(r.min) for r in bins), default=None),
        max=max((float(r.max) for r in bins), default=None),
        cp=cp(std, lower, upper),
        cpk=cpk(mean, std, lower, upper),
        out_of_limits=sum(int(r.outside) for r in bins),
        marginal=sum(int(r.marginal) for r in bins),
        histogram=Histogram(start=start, width=width, counts=counts),
    )


def _charts(limits: Row[Any], points: Sequence[Row[Any]]) -> list[ControlChart]:
    charts = []
    units = {name: spec.unit for name, spec in ((s.name, s) for s in PARAMETERS)}
    for name in COEFFICIENTS:
        mean, mr_bar = getattr(limits, name), getattr(limits, f"mr_{name}")
        if mean is None:
            continue
        lcl = ucl = mr_ucl = None
        if mr_bar is not None:
            lcl, ucl, mr_ucl = individuals_limits(float(mean), float(mr_bar))
        charts.append(
            ControlChart(
                name=name,
                unit=units[name],
                count=int(limits.n),
                mean=float(mean),
                mr_bar=None if mr_bar is None else float(mr_bar),
                lcl=lcl,
                ucl=ucl,
                mr_ucl=mr_ucl,
                points=[
                    ChartPoint(
                        started_at=p.started_at,
                        serial=p.serial,
                        value=getattr(p, name),
                        moving_range=getattr(p, f"mr_{name}"),
                    )
                    for p in points
                ],
            )
        )
    return charts


def eol_report(
    session: Session,
    filter: ReportFilter,
    *,
    profiles: Mapping[str, LimitsProfile] | None = None,
    unit_limit: int | None = None,
    chart_points: int = CHART_POINTS,
    now: datetime | None = None,
) -> EolReport:
    """The end-of-line report over the runs ``filter`` selects.

    Capability is measured against the profile of ``profiles`` (default: the shipped
    limits file) that :func:`station.report.bounds.choose_profile` picks for the runs in
    range; ``unit_limit`` cuts the unit list to the latest units.
    """
    queries = ReportQueries(session, filter)
    used = queries.limits_profiles()
    profile, bounds_source = choose_profile(used, profiles or load_profiles())
    bounds = profile_bounds(profile)
    overall = queries.summaries(by_station=False)[0]
    hours = _hours(filter, overall)
    poses = queries.pose_counts()
    bins: dict[str, list[Row[Any]]] = defaultdict(list)
    for source in ("runs", "poses"):
        for row in queries.parameter_bins(source, bounds):
            bins[row.name].append(row)
    units = [
        UnitVerdict(
            serial=row.serial,
            disposition="ship" if row.verdict == "pass" else "hold",
            verdict=row.verdict,
            runs=row.runs,
            last_started_at=row.started_at,
            station_id=row.station_id,
            operator_id=row.operator_id,
            failure=row.code,
        )
        for row in queries.latest_runs(unit_limit)
    ]
    return EolReport(
        generated_at=now or datetime.now(UTC),
        filter=filter,
        bounds_source=bounds_source,
        limits_profiles=used,
        summary=_summary(overall, sum(poses.values()), hours),
        stations=[
            StationSummary(
                station_id=row.station_id,
                summary=_summary(row, poses.get(row.station_id, 0), hours),
            )
            for row in queries.summaries(by_station=True)
        ],
        pareto=_pareto(queries.first_failures()),
        parameters=[_parameter(spec, bounds, bins[spec.name]) for spec in PARAMETERS],
        control_charts=_charts(queries.chart_limits(), queries.chart_points(chart_points)),
        units=units,
        units_total=int(overall.units),
    )
