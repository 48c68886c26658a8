"""The report's SQL over the runs a filter selects, one statement per section.

Nothing here walks runs in Python. Counts and yields, the Pareto and the parameter
statistics and histograms add up the daily roll-ups of :mod:`db.rollups` over the
whole days in range and the same aggregates over the runs of the partial days at its
ends, in one statement per section (``UNION ALL``, then grouped); the unit list and the
open holds walk ``ix_runs_started_at`` backwards. :mod:`db.report.reports` assembles
the report from these rows.
"""

from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from datetime import UTC, date, datetime, timedelta
from typing import Any

from sqlalchemy import (
    ColumnElement,
    Row,
    RowMapping,
    Select,
    and_,
    case,
    func,
    literal,
    or_,
    select,
    text,
    union_all,
)
from sqlalchemy.orm import Session, aliased

from db.models import ReportCounts, ReportFailures, ReportParameters, Run, RunFacts, RunFailure
from db.report.holds import unreviewed
from db.rollups import (
    COUNT_VALUES,
    FAILURE_VALUES,
    LIMITS,
    MOMENT_VALUES,
    PARAMETER_VALUES,
    PRODUCT_COUNT_VALUES,
    PRODUCTION,
    TREND_COUNT_VALUES,
    count_contributions,
    failure_contributions,
    parameter_contributions,
    stored_bounds,
)
from station.domain.calibration.uncertainty import COVERAGE_FACTOR
from station.domain.quality.days import LAST, day_number
from station.domain.quality.figures import (
    HOLD_AGES,
    CoefficientRisk,
    HoldCount,
    NearLimits,
    OpenHolds,
    ParameterStats,
    ReportFilter,
)
from station.domain.quality.parameters import COEFFICIENTS, FamilyBounds
from station.domain.quality.risk import decision_risks, normality

#: Day 0 of the roll-ups, and their length.
EPOCH = datetime(1970, 1, 1, tzinfo=UTC)
DAY = timedelta(days=1)

#: The fields of a filter that narrow the runs beyond time: a column of ``runs`` and of
#: the roll-ups each.
DIMENSIONS = ("station_id", "operator_id", "lot", "part_number")


def dimensions(filter: ReportFilter, columns: Any) -> list[ColumnElement[bool]]:
    """The station, operator, lot and product conditions of ``filter`` on ``columns``
    (``runs`` or a roll-up)."""
    return [
        getattr(columns, name) == value
        for name in DIMENSIONS
        if (value := getattr(filter, name)) is not None
    ]


def conditions(filter: ReportFilter) -> list[ColumnElement[bool]]:
    """The ``WHERE`` clauses on ``runs`` of ``filter``: production runs only (golden-unit
    checks are no production units)."""
    where = []
    if filter.since is not None:
        where.append(Run.started_at >= filter.since)
    if filter.until is not None:
        where.append(Run.started_at < filter.until)
    return [*where, PRODUCTION, *dimensions(filter, Run)]


#: A unit's latest attempt and its facts, joined beside the runs selected by :func:`_join_latest`.
LATEST = aliased(Run, name="latest")
LATEST_FACTS = aliased(RunFacts, name="latest_facts")


def _join_latest(stmt: Select[Any], serial: Any) -> Select[Any]:
    """``stmt`` joined with the latest attempt of the unit ``serial`` (:data:`LATEST`) and
    its facts (:data:`LATEST_FACTS`; :mod:`db.rollups`, ``line_latest``)."""
    return stmt.join(LATEST, LATEST.serial == serial).join(
        LATEST_FACTS, and_(LATEST_FACTS.run_pk == LATEST.id, LATEST_FACTS.line_latest.is_(True))
    )


class ReportQueries:
    """The report's queries over the runs ``filter`` selects, in the caller's session.

    The days the range covers whole come from the roll-ups of :mod:`db.rollups`, the
    partial days at its ends from the same aggregates computed over their runs; a
    statement adds both up.
    """

    def __init__(self, session: Session, filter: ReportFilter) -> None:
        self.session = session
        self.filter = filter
        #: The ``WHERE`` clauses on ``runs`` of the filter (:func:`conditions`).
        self.conditions = conditions(filter)
        self.days, self.edges = split_days(filter.since, filter.until)
        if session.get_bind().dialect.name == "postgresql":
            # The raw statements are scans with long expressions: compiling them (JIT)
            # cost seconds and saved nothing; their sorts and hashes spill to disk with
            # the default 4 MB of work memory.
            session.execute(text("SET LOCAL jit = off"))
            session.execute(text("SET LOCAL work_mem = '256MB'"))

    # -- helpers -----------------------------------------------------------------------

    def near_limits(
        self,
        bounds: FamilyBounds,
        parameters: Sequence[ParameterStats],
        values: Mapping[str, Sequence[float]],
    ) -> NearLimits:
        """The passing runs in range whose offset or sensitivity lies within its expanded
        uncertainty U (``runs.uncertainty``) of a bound of ``bounds``: accepted by the
        simple rule, refused by the guarded one; with the coefficients' decision risks
        (:func:`_risks`). One counting statement."""
        edges: list[ColumnElement[bool]] = []
        standard: list[Any] = []  # the mean U/k of each coefficient
        for family in ("offset", "sensitivity"):
            lower, upper = bounds.get(family, (None, None))
            for axis in "xyz":
                value = getattr(Run, f"{family}_{axis}")
                u = Run.uncertainty[(family, axis)].as_float()
                standard.append(func.avg(u / Run.uncertainty["k"].as_float()))
                if lower is not None:
                    edges.append(value - u < lower)
                if upper is not None:
                    edges.append(value + u > upper)
        edge = or_(*edges) if edges else literal(False)
        # A run without uncertainties holds JSON null, whose "k" reads as SQL NULL.
        carried = Run.uncertainty["k"].as_float().is_not(None)
        row = self.session.execute(
            select(
                func.count(),
                func.coalesce(func.sum(case((edge, 1), else_=0)), 0),
                func.count(func.distinct(case((edge, Run.serial), else_=None))),
                *standard,
            ).where(*self.conditions, Run.verdict == "pass", carried)
        ).one()
        return NearLimits(
            runs_passed=int(row[0]),
            within_u=int(row[1]),
            units=int(row[2]),
            risks=_risks(parameters, dict(zip(COEFFICIENTS, row[3:], strict=True)), values),
        )

    def _edge_conditions(self) -> list[ColumnElement[bool]] | None:
        """The runs of the partial days at the range's ends; ``None`` when there are none."""
        if not self.edges:
            return None
        spans = [and_(Run.started_at >= a, Run.started_at < b) for a, b in self.edges]
        return [or_(*spans), PRODUCTION, *dimensions(self.filter, Run)]

    def _rolled_conditions(self, table: Any) -> list[ColumnElement[bool]] | None:
        """The roll-up rows of the whole days in range; ``None`` when there are none."""
        if self.days is None:
            return None
        first, end = self.days
        where = dimensions(self.filter, table)
        if first is not None:
            where.append(table.day >= first)
        if end is not None:
            where.append(table.day < end)
        return where

    def _summed(
        self,
        table: Any,
        values: Mapping[str, str],
        group: Sequence[str],
        contributions: Callable[[list[ColumnElement[bool]]], Sequence[Select[Any]]],
        rolled_up: bool = True,
    ) -> list[Row[Any]]:
        """The ``values`` of ``table`` per ``group``: when ``rolled_up``, its roll-up rows
        over the whole days in range and the ``contributions`` (same columns) of the
        partial days' runs, else the contributions of every run in range; merged, sums
        added, minima and maxima kept."""
        if rolled_up:
            rolled, raw = self._rolled_conditions(table), self._edge_conditions()
        else:
            rolled, raw = None, self.conditions
        parts = [] if raw is None else list(contributions(raw))
        if rolled is not None:
            parts.append(
                select(
                    *(getattr(table, g) for g in group), *(getattr(table, v) for v in values)
                ).where(*rolled)
            )
        if not parts:
            return []
        merged = union_all(*parts).subquery("merged")
        keys = [merged.c[g] for g in group]
        stmt = select(
            *keys, *(getattr(func, how)(merged.c[v]).label(v) for v, how in values.items())
        ).group_by(*keys)
        return list(self.session.execute(stmt))

    # -- counts and yields -------------------------------------------------------------

    def station_counts(self) -> list[Row[Any]]:
        """Per station and limits profile: the sums of ``report_counts`` over the range.

        Runs, passes and station time; units counted at their first attempt on the line
        (``line_*``) with first and final passes; the station's retests (its attempts that
        are not their unit's first) and aborts; runs with coefficients and their moving
        ranges (:mod:`db.rollups`, the yield definition).
        """
        group = ["station_id", *LIMITS]
        rows = self._summed(
            ReportCounts, COUNT_VALUES, group, lambda where: [count_contributions(group, where)]
        )
        return sorted(rows, key=lambda row: tuple(row[: len(group)]))

    def product_counts(self) -> list[Row[Any]]:
        """Per part number: the counts :meth:`station_counts` sums per station (units,
        runs, passes, retests, aborts, station time), from the roll-ups and the partial
        days as theirs."""
        group, values = ["part_number"], PRODUCT_COUNT_VALUES
        rows = self._summed(
            ReportCounts, values, group, lambda w: [count_contributions(group, w, values=values)]
        )
        return sorted(rows, key=lambda row: str(row.part_number))

    # -- failures ----------------------------------------------------------------------

    def first_failures(self) -> list[Row[Any]]:
        """Failing runs per (first failure code, station, operator)."""
        group = ["code", "station_id", "operator_id"]
        return self._summed(
            ReportFailures, FAILURE_VALUES, group, lambda w: [failure_contributions(group, w)]
        )

    # -- parameters --------------------------------------------------------------------

    def parameters(self, bounds: FamilyBounds) -> tuple[dict[str, RowMapping], bool]:
        """Per parameter: n, Σ(x − c), Σ(x − c)², min, max, out of limits, marginal and
        histogram bins against ``bounds`` (:func:`db.rollups.parameter_contributions`),
        and whether the roll-ups answered.

        The roll-ups answer when they were counted with ``bounds``; otherwise every run
        in range is aggregated (seconds over a long history), and the report says so.
        """
        rolled_up = stored_bounds(self.session.connection()) == bounds
        rows = self._summed(
            ReportParameters,
            PARAMETER_VALUES,
            ["parameter"],
            lambda where: parameter_contributions([], where, bounds),
            rolled_up,
        )
        return {row.parameter: row._mapping for row in rows}, rolled_up

    # -- trend -------------------------------------------------------------------------

    def daily_counts(self, day: ColumnElement[int] | None) -> list[Row[Any]]:
        """The sums of ``report_counts`` per day: the roll-ups' UTC days (``day`` ``None``)
        or the plant's days ``day`` numbers the runs with (from the runs)."""
        values, columns = TREND_COUNT_VALUES, None if day is None else {"day": day}
        return self._summed(
            ReportCounts,
            values,
            ["day"],
            lambda w: [count_contributions(["day"], w, columns=columns, values=values)],
            rolled_up=day is None,
        )

    def daily_parameters(
        self, bounds: FamilyBounds, day: ColumnElement[int] | None
    ) -> list[Row[Any]]:
        """The parameters' sums per parameter and day (as :meth:`daily_counts`): only
        :data:`MOMENT_VALUES`, for the Cpk."""
        rolled_up = day is None and stored_bounds(self.session.connection()) == bounds
        columns = None if day is None else {"day": day}
        return self._summed(
            ReportParameters,
            MOMENT_VALUES,
            ["parameter", "day"],
            lambda w: parameter_contributions(["day"], w, bounds, columns, moments_only=True),
            rolled_up,
        )

    # -- units -------------------------------------------------------------------------

    def _selected(self, held: bool) -> list[ColumnElement[bool]]:
        """The units the report counts, by their first attempt on the line: that run is
        in range and matches the filter (``held``: and the unit's latest attempt, wherever
        and whenever it was, failed). The yield table counts the same units."""
        where: list[ColumnElement[bool]] = [RunFacts.line_first.is_(True), *self.conditions]
        return [*where, RunFacts.line_final_pass.is_(False)] if held else where

    def latest_runs(self, limit: int | None, offset: int = 0, held: bool = False) -> list[Row[Any]]:
        """The units the yield table counts (``held``: those on hold), newest first attempt
        first, each with its latest attempt (wherever and whenever it was), run count and
        that run's first failure code; ``offset`` skips the newest (a page)."""
        # The page first (the units' first runs, cheap conditions: a walk of
        # ix_runs_started_at, OFFSET included), then the latest run of its units only.
        page = (
            select(
                Run.id.label("first_id"),
                Run.started_at.label("first_start"),
                Run.serial,
                RunFacts.line_final_pass.label("shipped"),
                RunFacts.unit_runs.label("runs"),
            )
            .join(RunFacts, RunFacts.run_pk == Run.id)
            .where(*self._selected(held))
            .order_by(Run.started_at.desc(), Run.id.desc())
            .limit(limit)
            .offset(offset or None)
            .subquery("page")
        )
        stmt = select(
            LATEST.id,
            page.c.serial,
            page.c.shipped,
            LATEST.verdict,
            LATEST.started_at,
            LATEST.station_id,
            LATEST.operator_id,
            page.c.runs,
            LATEST_FACTS.first_failure.label("code"),
        )
        newest = (page.c.first_start.desc(), page.c.first_id.desc())
        return list(self.session.execute(_join_latest(stmt, page.c.serial).order_by(*newest)))

    def open_holds(self, now: datetime) -> OpenHolds:
        """The held units the yield table counts whose failed latest attempt no review has
        closed, counted by the age of that run at ``now`` and by its first failure reason:
        one grouped statement (the held units' first runs, then each one's latest run)."""
        day, week = now - timedelta(days=1), now - timedelta(days=7)
        young, middle, old = HOLD_AGES
        age = case(
            (LATEST.started_at >= day, young), (LATEST.started_at >= week, middle), else_=old
        ).label("age")
        code = func.coalesce(LATEST_FACTS.first_failure, "").label("code")
        runs = (
            select(age, code, func.count().label("units"))
            .select_from(Run)
            .join(RunFacts, RunFacts.run_pk == Run.id)
        )
        stmt = (
            _join_latest(runs, Run.serial)
            .where(*self._selected(True), LATEST.verdict == "fail", unreviewed(LATEST))
            .group_by(age, code)
        )
        ages: Counter[str] = Counter()
        causes: Counter[str] = Counter()
        for row in self.session.execute(stmt):
            ages[row.age] += row.units
            causes[row.code or "unknown"] += row.units
        return OpenHolds(
            total=sum(ages.values()),
            by_age=[HoldCount(label=label, units=ages[label]) for label in HOLD_AGES],
            by_cause=[
                HoldCount(label=label, units=n)
                for label, n in sorted(causes.items(), key=lambda item: (-item[1], item[0]))
            ],
        )

    def failing_runs(self, code: str, limit: int) -> Sequence[Any]:
        """The latest ``limit`` failing runs in range whose first failure reason is
        ``code`` (a Pareto bar's runs), newest first, with that reason."""
        stmt = (
            select(
                Run.run_id,
                Run.started_at,
                Run.serial,
                Run.station_id,
                Run.operator_id,
                Run.lot,
                RunFailure.code,
                RunFailure.message,
                RunFailure.measured,
                RunFailure.lower,
                RunFailure.upper,
                RunFailure.axis,
                RunFailure.pose,
                RunFailure.uncertainty,
            )
            .join(RunFailure, and_(RunFailure.run_pk == Run.id, RunFailure.position == 0))
            .where(Run.verdict == "fail", RunFailure.code == code, *self.conditions)
            .order_by(Run.started_at.desc(), Run.id.desc())
            .limit(limit)
        )
        return self.session.execute(stmt).all()


def _risks(
    parameters: Sequence[ParameterStats],
    u_means: Mapping[str, float | None],
    values: Mapping[str, Sequence[float]],
) -> list[CoefficientRisk]:
    """Each coefficient's global decision risks under both rules (:mod:`station.domain.
    quality.risk`), from its spread in range and the runs' mean standard uncertainty,
    with the normality check of its latest ``values`` the risks' model assumes."""
    risks = []
    for stats in parameters:
        u = u_means.get(stats.name)
        if u is None or stats.mean is None or stats.std is None:
            continue
        u = float(u)
        simple = decision_risks(stats.mean, stats.std, u, stats.lower, stats.upper)
        guarded = decision_risks(
            stats.mean, stats.std, u, stats.lower, stats.upper, guard=COVERAGE_FACTOR * u
        )
        check = normality(values.get(stats.name, ()))
        risks.append(
            CoefficientRisk(
                name=stats.name,
                u=u,
                simple_false_accept=simple.false_accept,
                simple_false_reject=simple.false_reject,
                guarded_false_accept=guarded.false_accept,
                guarded_false_reject=guarded.false_reject,
                normality_statistic=None if check is None else check.statistic,
                normality_p_value=None if check is None else check.p_value,
                normality_values=0 if check is None else check.values,
                normal=None if check is None else check.normal,
            )
        )
    return risks


def split_days(
    since: datetime | None, until: datetime | None
) -> tuple[tuple[int | None, int | None] | None, list[tuple[datetime, datetime]]]:
    """The whole UTC days in ``[since, until)`` as ``(first, end)`` day numbers (``None``
    for an open side; ``None`` altogether when no day is whole) and the partial days at
    the ends as time spans."""
    first = None if since is None else -((EPOCH - since) // DAY)
    end = None if until is None else (until - EPOCH) // DAY
    edges = []
    if since is not None and first is not None:
        if until is not None and end is not None and first >= end:
            return None, [(since, until)] if since < until else []
        if since < _day_start(first):
            edges.append((since, _day_start(first)))
    if until is not None and end is not None and _day_start(end) < until:
        edges.append((_day_start(end), until))
    return (first, end), edges


def _day_start(day: int) -> datetime:
    """The start of the roll-ups' ``day``; the calendar's end (:data:`LAST`) for the day
    after its last date, which a moment of that date rounds up to."""
    return EPOCH + day * DAY if day <= day_number(date.max) else LAST
