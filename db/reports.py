"""Aggregation queries of the end-of-line report, one SQL statement per section.

Nothing here walks runs in Python: counts and yields come from one grouped query over
windows (``row_number``/``lead`` per unit, ordered by start time), the Pareto from the
first failure reason of each failing run grouped by code, station and operator, the
parameter statistics and histograms from one grouped query per limits family (grouped
by the histogram bin of each axis), the control-chart limits from ``lag`` over the runs
in time order, the unit list from ``row_number`` per serial. Python only merges the
grouped rows (stations, bins: a few hundred) and applies the capability formulas of
:mod:`station.report.capability`.
"""

from collections import defaultdict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any

from sqlalchemy import (
    ColumnElement,
    Float,
    Integer,
    Row,
    and_,
    case,
    cast,
    extract,
    false,
    func,
    or_,
    select,
    text,
    type_coerce,
)
from sqlalchemy.orm import Session

from db.models import Pose, Run, RunFailure
from station.limits import LimitsProfile, load_profiles
from station.records import LimitsRef
from station.report.bounds import (
    COEFFICIENTS,
    FAMILIES,
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

#: Points drawn on each control chart (the latest runs); its limits use every run.
CHART_POINTS = 200


class ReportQueries:
    """The report's queries over the runs ``filter`` selects, in the caller's session."""

    def __init__(self, session: Session, filter: ReportFilter) -> None:
        self.session = session
        self.filter = filter
        self.dialect = session.get_bind().dialect.name
        if self.dialect == "postgresql":
            # The report's statements are scans with long expressions: compiling them
            # (JIT) cost seconds and saved nothing; its sorts and hashes of a million
            # rows spill to disk with the default 4 MB of work memory.
            session.execute(text("SET LOCAL jit = off"))
            session.execute(text("SET LOCAL work_mem = '256MB'"))

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

    def station_counts(self) -> list[Row[Any]]:
        """Per station: runs, passes, station time, and units with their first and final
        passes, both within the station and on the whole line (``line_*``).

        Each run is ranked within its unit at the station and within its unit on the
        line by ``(started_at, id)``: rank 1 is the unit's first run, a run without a
        ``lead`` its latest. A unit's first (latest) run on the line is at exactly one
        station, so the ``line_*`` columns add up across stations to the line's counts.
        """
        order = (Run.started_at, Run.id)
        # Serial first: sorts compare serial numbers with abbreviated keys, and the
        # station window can reuse the line window's order (incremental sort).
        at_station, on_line = [Run.serial, Run.station_id], [Run.serial]
        ranked = (
            select(
                Run.station_id,
                Run.verdict,
                Run.started_at,
                Run.finished_at,
                self._seconds().label("seconds"),
                func.row_number().over(partition_by=at_station, order_by=order).label("nth"),
                func.lead(Run.id).over(partition_by=at_station, order_by=order).label("next"),
                func.row_number().over(partition_by=on_line, order_by=order).label("line_nth"),
                func.lead(Run.id).over(partition_by=on_line, order_by=order).label("line_next"),
            )
            .where(*self.conditions())
            .subquery("ranked")
        )
        c = ranked.c
        passed = c.verdict == "pass"

        def count_if(*conditions: ColumnElement[bool]) -> ColumnElement[int]:
            return func.sum(case((and_(*conditions), 1), else_=0))

        stmt = (
            select(
                c.station_id,
                func.count().label("runs"),
                count_if(passed).label("runs_passed"),
                func.sum(c.seconds).label("seconds"),
                func.min(c.started_at).label("first_start"),
                func.max(c.finished_at).label("last_finish"),
                count_if(c.nth == 1).label("units"),
                count_if(c.nth == 1, passed).label("first_pass"),
                count_if(c.next.is_(None), passed).label("final_pass"),
                count_if(c.line_nth == 1).label("line_units"),
                count_if(c.line_nth == 1, passed).label("line_first_pass"),
                count_if(c.line_next.is_(None), passed).label("line_final_pass"),
            )
            .group_by(c.station_id)
            .order_by(c.station_id)
        )
        return list(self.session.execute(stmt).all())

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

    def family_bins(self, family: str, bounds: Bounds) -> list[Row[Any]]:
        """The parameters of one limits family (up to three axes), in one scan.

        Grouped by the histogram bin of every axis at once (bins ``b0, b1, …``), each
        group holds per axis ``i``: count ``n{i}``, Σ(x − c) ``sum{i}``, Σ(x − c)²
        ``squares{i}`` (c the centre of the tolerance), ``min{i}``, ``max{i}``, values out
        of limits ``outside{i}`` and marginal values ``marginal{i}``. Sums, counts, minima
        and maxima add up across groups, so the caller merges the groups (at most 30³,
        in practice a few hundred) into each axis' statistics and histogram. Poses are
        grouped by station as well, which gives the pose count per station.
        """
        specs = _of_family(family)
        lower, upper = bounds[family]
        start, width, bins = histogram_bins(lower, upper)
        zone_low, zone_high = marginal_zones(lower, upper)
        low, high = tolerance(lower, upper)
        centre = (low + high) / 2
        picked: list[ColumnElement[Any]] = [
            self._value(spec).label(f"x{i}") for i, spec in enumerate(specs)
        ]
        if specs[0].source == "poses":
            picked.append(Run.station_id.label("station_id"))
        values = select(*picked)
        if specs[0].source == "poses":
            values = values.select_from(Pose).join(Run, Pose.run_pk == Run.id)
        values = values.where(*self.conditions())
        if family == "gyro_bias":
            # OFFSET 0 keeps PostgreSQL from inlining the values into every aggregate (a
            # bias would be read out of its JSON document thirty times a row); columns
            # are inlined, which keeps the scan parallel.
            values = values.offset(0)
        v = values.subquery("v")
        groups: list[ColumnElement[Any]] = []
        columns: list[ColumnElement[Any]] = []
        for i in range(len(specs)):
            x = v.c[f"x{i}"]
            groups.append(
                case(
                    (x < start, 0),
                    (x >= start + width * bins, bins - 1),
                    else_=cast(func.floor((x - start) / width), Integer),
                ).label(f"b{i}")
            )
            outside = or_(
                false() if lower is None else x < lower, false() if upper is None else x > upper
            )
            near = or_(
                false() if lower is None else x < zone_low,
                false() if upper is None else x > zone_high,
            )
            deviation = x - centre
            columns += [
                func.count(x).label(f"n{i}"),
                func.sum(deviation).label(f"sum{i}"),
                func.sum(deviation * deviation).label(f"squares{i}"),
                func.min(x).label(f"min{i}"),
                func.max(x).label(f"max{i}"),
                func.sum(case((outside, 1), else_=0)).label(f"outside{i}"),
                func.sum(case((and_(~outside, near), 1), else_=0)).label(f"marginal{i}"),
            ]
        if specs[0].source == "poses":
            # Grouped by station too: the pose counts per station come with it.
            groups.append(v.c.station_id)
        stmt = select(*groups, *columns).group_by(*groups)
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


@dataclass(frozen=True)
class _Counts:
    """What a summary is computed from (one station, or the line)."""

    runs: int
    runs_passed: int
    units: int
    first_pass: int
    final_pass: int
    seconds: float | None
    poses: int


def _station(row: Row[Any], poses: int) -> _Counts:
    return _Counts(
        runs=int(row.runs),
        runs_passed=int(row.runs_passed),
        units=int(row.units),
        first_pass=int(row.first_pass),
        final_pass=int(row.final_pass),
        seconds=float(row.seconds),
        poses=poses,
    )


def _line(rows: Sequence[Row[Any]], poses: int) -> _Counts:
    return _Counts(
        runs=sum(int(r.runs) for r in rows),
        runs_passed=sum(int(r.runs_passed) for r in rows),
        units=sum(int(r.line_units) for r in rows),
        first_pass=sum(int(r.line_first_pass) for r in rows),
        final_pass=sum(int(r.line_final_pass) for r in rows),
        seconds=sum(float(r.seconds) for r in rows) if rows else None,
        poses=poses,
    )


def _summary(n: _Counts, hours: float | None) -> Summary:
    retests = n.runs - n.units
    seconds = n.seconds
    return Summary(
        runs=n.runs,
        runs_passed=n.runs_passed,
        units_tested=n.units,
        units_passed=n.final_pass,
        units_failed=n.units - n.final_pass,
        first_pass_units=n.first_pass,
        report_yield=_ratio(n.runs_passed, n.runs),
        first_pass_yield=_ratio(n.first_pass, n.units),
        final_yield=_ratio(n.final_pass, n.units),
        retests=retests,
        retest_rate=_ratio(retests, n.units),
        hours=hours,
        units_per_hour=_ratio(n.units, hours) if hours else None,
        cycle_time_per_run_s=_ratio(seconds, n.runs) if seconds is not None else None,
        cycle_time_per_unit_s=_ratio(seconds, n.units) if seconds is not None else None,
        cycle_time_per_pose_s=_ratio(seconds, n.poses) if seconds is not None else None,
        poses=n.poses,
    )


def _hours(filter: ReportFilter, rows: Sequence[Row[Any]]) -> float | None:
    start = filter.since or min((r.first_start for r in rows), default=None)
    end = filter.until or max((r.last_finish for r in rows), default=None)
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


def _parameter(
    spec: ParameterSpec, axis: int, bounds: Bounds, groups: Sequence[Row[Any]]
) -> ParameterStats:
    """Merge the grouped rows of :meth:`ReportQueries.family_bins` for one axis."""
    lower, upper = bounds[spec.family]
    start, width, n_bins = histogram_bins(lower, upper)
    low, high = tolerance(lower, upper)
    counts = [0] * n_bins
    rows = [row._mapping for row in groups if row._mapping[f"n{axis}"]]
    for row in rows:
        counts[row[f"b{axis}"]] += int(row[f"n{axis}"])
    count = sum(counts)
    mean, std = shifted_moments(
        count,
        sum(float(row[f"sum{axis}"]) for row in rows),
        sum(float(row[f"squares{axis}"]) for row in rows),
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
        min=min((float(row[f"min{axis}"]) for row in rows), default=None),
        max=max((float(row[f"max{axis}"]) for row in rows), default=None),
        cp=cp(std, lower, upper),
        cpk=cpk(mean, std, lower, upper),
        out_of_limits=sum(int(row[f"outside{axis}"]) for row in rows),
        marginal=sum(int(row[f"marginal{axis}"]) for row in rows),
        histogram=Histogram(start=start, width=width, counts=counts),
    )


def _of_family(family: str) -> list[ParameterSpec]:
    return [spec for spec in PARAMETERS if spec.family == family]


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
    stations = queries.station_counts()
    hours = _hours(filter, stations)
    families = {family: queries.family_bins(family, bounds) for family in FAMILIES}
    poses: dict[str, int] = defaultdict(int)
    for row in families["pose_noise"]:
        poses[row.station_id] += row.n0
    axes = {spec.name: i for family in FAMILIES for i, spec in enumerate(_of_family(family))}
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
        summary=_summary(_line(stations, sum(poses.values())), hours),
        stations=[
            StationSummary(
                station_id=row.station_id,
                summary=_summary(_station(row, poses[row.station_id]), hours),
            )
            for row in stations
        ],
        pareto=_pareto(queries.first_failures()),
        parameters=[
            _parameter(spec, axes[spec.name], bounds, families[spec.family]) for spec in PARAMETERS
        ],
        control_charts=_charts(queries.chart_limits(), queries.chart_points(chart_points)),
        units=units,
        units_total=sum(int(row.line_units) for row in stations),
    )
