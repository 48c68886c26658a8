"""The end-of-line report's derived data: per-run facts and daily roll-ups, kept exact.

Every table here is a function of ``runs``, ``poses`` and ``run_failures``, defined once
as SQL in this module and computed by that SQL in three places: :func:`rebuild` (every
run: the migration, the benchmark), :func:`record_run` (one submission, in its
transaction) and the report's edges (:mod:`db.report.reports`: runs in a partial day).

- ``run_facts``: per run, its first failure code, pose count, gyro bias, whether it is
  an attempt and its unit's first or latest attempt, whether the unit's latest attempt
  passed (on its first attempt), the unit's run count and the previous run of the line
  with coefficients.
- ``report_counts``, ``report_failures``, ``report_parameters``: per day (UTC) × station ×
  operator × lot × product (part number), the sums, minima and maxima of what each run
  contributes (counts, first and final passes, retests, aborts, moving ranges; failing
  runs by first reason; n, Σ(x − c), Σ(x − c)², min, max and histogram bins of every
  parameter).

**The yield definition**, the one every yield figure (the report's summary, station,
product and trend rows, the what-if, the units list, open holds, the dashboard's units
on hold, the yield alert) reads from these facts:

- an **attempt** is a production run (not a golden-unit check) that the operator did not
  abort. An abort is a run, never an attempt: it wrote nothing into the unit and says
  nothing about it (:func:`station.domain.record.unit_state.counts`, the unit answers' rule);
  it is counted apart (``aborts``);
- a unit's **first attempt** is its earliest attempt ever, its **latest attempt** its
  latest ever, wherever and whenever they are. A unit counts in the cohort (units
  tested) of the selection that holds its first attempt, with its first-pass (that
  attempt passed) and its final pass (its latest attempt passed); a selection that holds
  only later attempts of a unit counts them as retests and not the unit. A unit with
  nothing but aborts was never attempted: in no cohort, never on hold;
- **retests** are attempts that are not their unit's first attempt, each counted at its
  own station, day and product: so a station's retests are its own attempts, and the
  stations' retests add up to the line's.

A submission can change facts of runs stored before it: a late run becomes its unit's
first, a retest makes the previous run no longer the latest, a run slotted in between
changes the next charted run's moving range. A station's golden-unit check
(``runs.purpose`` = ``golden``) is no production unit: it has no facts and is in no
roll-up, and no moving range reaches over it. :func:`record_run` takes those runs'
contributions out of the roll-ups, recomputes their facts and adds them back, so the
roll-ups always equal the aggregate of the facts. Counts and times are integers
(station time in milliseconds), so taking out and adding back is exact.
"""

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from typing import Any

from sqlalchemy import (
    BigInteger,
    BindParameter,
    ColumnElement,
    Connection,
    Double,
    Executable,
    FromClause,
    Integer,
    Select,
    String,
    and_,
    bindparam,
    case,
    cast,
    delete,
    exists,
    func,
    insert,
    literal,
    literal_column,
    null,
    or_,
    select,
    text,
    true,
    tuple_,
    union,
    union_all,
)
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.ext.compiler import compiles
from sqlalchemy.orm import InstrumentedAttribute, aliased
from sqlalchemy.sql.compiler import SQLCompiler
from sqlalchemy.sql.functions import FunctionElement
from sqlalchemy.sql.visitors import InternalTraversal

from db.models import (
    ReportBounds,
    ReportCounts,
    ReportFailures,
    ReportParameters,
    Run,
    RunFacts,
    RunFailure,
    RunPose,
    StoredLimitsProfile,
)
from station.domain.product.limits import LimitsProfile
from station.domain.quality.capability import (
    HISTOGRAM_BINS,
    histogram_bins,
    marginal_zones,
    tolerance,
)
from station.domain.quality.parameters import (
    COEFFICIENTS,
    PARAMETERS,
    FamilyBounds,
    ParameterSpec,
    profile_bounds,
)
from station.domain.record.unit_state import ABORTED

#: The key of every roll-up row (a UTC day, station, operator, lot, product);
#: ``report_counts`` adds the limits profile.
BUCKET = ("day", "station_id", "operator_id", "lot", "part_number")
LIMITS = ("limits_name", "limits_version", "limits_sha256")
#: The keys of ``report_counts`` and ``report_failures`` rows.
COUNT_KEYS = (*BUCKET, *LIMITS)
FAILURE_KEYS = (*BUCKET, "code")

#: Histogram bin columns of ``report_parameters``.
HISTOGRAM = tuple(f"h{i:02d}" for i in range(HISTOGRAM_BINS))

#: Where each report parameter (:data:`station.domain.quality.parameters.PARAMETERS`) is stored:
#: one value per run (a column of ``runs`` or ``run_facts``) or one per pose (``poses``).
PER_RUN: dict[str, InstrumentedAttribute[float | None]] = {
    **{f"offset_{a}": getattr(Run, f"offset_{a}") for a in "xyz"},
    **{f"sensitivity_{a}": getattr(Run, f"sensitivity_{a}") for a in "xyz"},
    "verification_error": Run.verification_error_mg,
    **{f"gyro_bias_{a}": getattr(RunFacts, f"gyro_bias_{a}") for a in "xyz"},
}
PER_POSE: dict[str, InstrumentedAttribute[float | None]] = {
    f"pose_noise_{a}": getattr(RunPose, f"std_{a}") for a in "xyz"
}

#: A run's poses: by its key and its start, so that PostgreSQL reads the run's year of
#: ``poses`` only (both tables are partitioned by year, :mod:`db.partitions`).
OWN_POSES = and_(RunPose.run_pk == Run.id, RunPose.started_at == Run.started_at)

#: The pose noise of a run summed over its poses (``run_facts``), by fact column: a
#: trend's moments of the per-pose parameters read these, one row per run.
NOISE_TOTALS: dict[str, ColumnElement[float]] = {
    **{f"noise_sum_{a}": getattr(RunPose, f"std_{a}") for a in "xyz"},
    **{
        f"noise_squares_{a}": getattr(RunPose, f"std_{a}") * getattr(RunPose, f"std_{a}")
        for a in "xyz"
    },
}

#: How each value column merges across rows: ``sum``, ``min`` or ``max``.
COUNT_VALUES: dict[str, str] = {
    **dict.fromkeys(("runs", "runs_passed", "duration_ms", "poses"), "sum"),
    "first_start": "min",
    "last_finish": "max",
    **dict.fromkeys(
        ("line_units", "line_first_pass", "line_final_pass", "retests", "aborts", "charted"), "sum"
    ),
    **{f"mr_{name}": "sum" for name in COEFFICIENTS},
}
#: The columns a trend reads (:mod:`db.report.trends`): no moving ranges, so no earlier run.
TREND_COUNT_VALUES: dict[str, str] = {
    name: COUNT_VALUES[name]
    for name in ("runs", "runs_passed", "line_units", "line_first_pass", "line_final_pass")
}
#: The columns a product's summary reads: all but the first start, the last finish and
#: the control charts' (charted runs, moving ranges).
PRODUCT_COUNT_VALUES: dict[str, str] = {
    name: merge
    for name, merge in COUNT_VALUES.items()
    if name not in ("first_start", "last_finish", "charted") and not name.startswith("mr_")
}
FAILURE_VALUES: dict[str, str] = {"runs": "sum"}
#: The columns a mean and spread (and Cpk) need, all added up.
MOMENT_VALUES: dict[str, str] = {"n": "sum", "sum": "sum", "squares": "sum"}
PARAMETER_VALUES: dict[str, str] = {
    **MOMENT_VALUES,
    "min": "min",
    "max": "max",
    "outside": "sum",
    "marginal": "sum",
    **dict.fromkeys(HISTOGRAM, "sum"),
}


class utc_day(FunctionElement[int]):  # noqa: N801 (an SQL function)
    """Days from 1970-01-01 to the UTC date of a moment (the roll-ups' ``day``)."""

    type = Integer()
    inherit_cache = True


@compiles(utc_day, "postgresql")
def _utc_day_pg(element: utc_day, compiler: SQLCompiler, **kw: Any) -> str:
    moment = compiler.process(element.clauses, **kw)
    return f"((({moment}) AT TIME ZONE 'UTC')::date - DATE '1970-01-01')"


def _sqlite_moment(moment: str) -> str:
    """A stored SQLite moment (``YYYY-MM-DD HH:MM:SS.ffffff``, UTC) as its date functions
    can read it for any moment of the years 1…9999: cut to milliseconds.

    Those functions round a moment to milliseconds first, and the last half millisecond
    of 9999 rounds into a year they do not hold: they answer NULL, which the roll-ups'
    NOT NULL columns refuse. Cut, it never leaves its year.
    """
    return f"substr({moment}, 1, 23)"


@compiles(utc_day, "sqlite")
def _utc_day_sqlite(element: utc_day, compiler: SQLCompiler, **kw: Any) -> str:
    moment = _sqlite_moment(compiler.process(element.clauses, **kw))
    return f"CAST(julianday(date({moment})) - 2440587.5 AS INTEGER)"


class duration_ms(FunctionElement[int]):  # noqa: N801 (an SQL function)
    """Milliseconds from the first moment to the second, rounded."""

    type = BigInteger()
    inherit_cache = True


@compiles(duration_ms, "postgresql")
def _duration_ms_pg(element: duration_ms, compiler: SQLCompiler, **kw: Any) -> str:
    start, end = (compiler.process(c, **kw) for c in element.clauses)
    return f"round(extract(epoch FROM ({end}) - ({start})) * 1000)::bigint"


@compiles(duration_ms, "sqlite")
def _duration_ms_sqlite(element: duration_ms, compiler: SQLCompiler, **kw: Any) -> str:
    start, end = (_sqlite_moment(compiler.process(c, **kw)) for c in element.clauses)
    return f"CAST(round((julianday({end}) - julianday({start})) * 86400000.0) AS INTEGER)"


class smaller(FunctionElement[Any]):  # noqa: N801 (an SQL function)
    """The smaller of two values (``least`` / two-argument ``min``)."""

    inherit_cache = True


class larger(FunctionElement[Any]):  # noqa: N801 (an SQL function)
    """The larger of two values (``greatest`` / two-argument ``max``)."""

    inherit_cache = True


class exact_double(ColumnElement[float]):  # noqa: N801 (an SQL constant)
    """A float constant, read back exactly by the database.

    PostgreSQL gets it in the statement's text: it reads decimal text correctly
    rounded, and ``repr`` gives the digits that round back to the same double. SQLite's
    reading of decimal text is not always correctly rounded (1e-303 and some values
    near 1e90 come back a bit off): there it stays a bound parameter.
    """

    type = Double()
    inherit_cache = True
    _traverse_internals = [("value", InternalTraversal.dp_plain_obj)]  # noqa: RUF012

    def __init__(self, value: float) -> None:
        self.value = value


@compiles(exact_double, "postgresql")
def _exact_double_pg(element: exact_double, compiler: SQLCompiler, **kw: Any) -> str:
    return f"CAST({element.value!r} AS DOUBLE PRECISION)"


@compiles(exact_double)
def _exact_double(element: exact_double, compiler: SQLCompiler, **kw: Any) -> str:
    return compiler.process(literal(element.value, Double()), **kw)


#: The pairwise functions' names: on PostgreSQL, on SQLite.
_PAIRWISE = {smaller: ("least", "min"), larger: ("greatest", "max")}


@compiles(smaller)
@compiles(larger)
def _pairwise(element: smaller | larger, compiler: SQLCompiler, **kw: Any) -> str:
    on_postgresql, on_sqlite = _PAIRWISE[type(element)]
    name = on_postgresql if compiler.dialect.name == "postgresql" else on_sqlite
    return f"{name}({compiler.process(element.clauses, **kw)})"


# -- per-run facts ---------------------------------------------------------------------


#: Text safe to write between quotes: no quote to escape, no % for the driver to read
#: as a placeholder.
_SAFE_TEXT = re.compile(r"[A-Za-z0-9_.-]*")


def _inline(value: float | str | None) -> ColumnElement[Any]:
    """``value`` written into the statement's text, not bound as a parameter.

    The roll-up statements hold hundreds of constants: histogram bins, limits, the 1 and
    0 of every count. Bound, each is a parameter that SQLAlchemy and the driver convert
    on every execution; the parameters statement of a submission took 1.6 ms of CPU
    with its 391 parameters and 0.2 ms with them inline. Floats: see
    :class:`exact_double`.

    Kept for the submissions target of ``docs/benchmarks.md`` (submissions as fast as
    before, within noise): with every constant bound instead (plain ``literal``), a
    submission took 7.2 and 7.4 ms of CPU in the server's process against 4.7 and
    5.4 ms inline (``benchmarks/bench_submit.py --runs 20000``, medians of 200 new
    units' runs, the two forms back to back twice on a loaded machine), about a fifth
    of the submissions/s through the API.
    """
    if value is None:
        return null()
    if isinstance(value, str):
        if not _SAFE_TEXT.fullmatch(value):
            raise ValueError(f"not a constant to write into SQL: {value!r}")
        return literal_column(f"'{value}'", String())
    if isinstance(value, int):
        return literal_column(str(value), Integer())
    return exact_double(float(value))


_PASS, _FAIL, _ZERO, _ONE = _inline("pass"), _inline("fail"), _inline(0), _inline(1)
_ABORTED = _inline(ABORTED)
#: The runs the report counts: production units, never a station's golden-unit checks.
PRODUCTION = Run.purpose.is_(None)


def aborted(run_pk: Any) -> ColumnElement[bool]:
    """Whether the run ``run_pk`` was aborted by the operator (one of its failures says
    so): it says nothing about the unit, is no attempt and no failure of it
    (:func:`station.domain.record.unit_state.counts`; the yield definition above)."""
    failure = aliased(RunFailure, name="abort")  # apart from a RunFailure outside
    return exists().where(failure.run_pk == run_pk, failure.code == _ABORTED)


def _facts(where: Sequence[ColumnElement[bool]]) -> Select[Any]:
    """The ``run_facts`` rows of the runs ``where`` selects (see :class:`RunFacts`), by
    the yield definition of this module."""
    other = aliased(Run, name="other")
    earlier = tuple_(other.started_at, other.id) < tuple_(Run.started_at, Run.id)
    later = tuple_(other.started_at, other.id) > tuple_(Run.started_at, Run.id)
    unit = other.serial == Run.serial
    newest = (other.started_at.desc(), other.id.desc())
    attempt = ~aborted(Run.id)
    # The unit's attempts: its production runs the operator did not abort.
    unit_attempt = and_(unit, other.purpose.is_(None), ~aborted(other.id))
    line_first = and_(attempt, ~exists().where(unit_attempt, earlier))
    latest_verdict = (
        select(other.verdict).where(unit_attempt).order_by(*newest).limit(1).scalar_subquery()
    )
    return select(
        Run.id,
        select(RunFailure.code)
        .where(RunFailure.run_pk == Run.id, RunFailure.position == 0)
        .scalar_subquery(),
        select(func.count()).select_from(RunPose).where(OWN_POSES).scalar_subquery(),
        *(Run.gyro[("bias", a)].as_float() for a in "xyz"),
        *(
            select(func.sum(total)).where(OWN_POSES).scalar_subquery()
            for total in NOISE_TOTALS.values()
        ),
        attempt,
        line_first,
        and_(attempt, ~exists().where(unit_attempt, later)),
        and_(line_first, latest_verdict == _PASS),
        select(func.count()).select_from(other).where(unit).scalar_subquery(),
        case(
            (
                Run.offset_x.is_not(None),
                select(other.id)
                .where(other.offset_x.is_not(None), other.purpose.is_(None), earlier)
                .order_by(*newest)
                .limit(1)
                .scalar_subquery(),
            ),
        ),
    ).where(*where)


_FACT_COLUMNS = (
    "run_pk",
    "first_failure",
    "poses",
    *(f"gyro_bias_{a}" for a in "xyz"),
    *NOISE_TOTALS,
    "attempt",
    "line_first",
    "line_latest",
    "line_final_pass",
    "unit_runs",
    "chart_previous",
)


# -- contributions: what runs add to each roll-up ----------------------------------------


def _keys(names: Sequence[str], extra: dict[str, Any]) -> list[ColumnElement[Any]]:
    columns: dict[str, Any] = {
        "day": utc_day(Run.started_at),
        "station_id": Run.station_id,
        "operator_id": Run.operator_id,
        "lot": func.coalesce(Run.lot, _inline("")),
        "part_number": Run.part_number,
        **{name: getattr(Run, name) for name in LIMITS},
        **extra,
    }
    return [columns[name].label(name) for name in names]


def _count_if(condition: ColumnElement[bool] | InstrumentedAttribute[bool]) -> ColumnElement[int]:
    return func.coalesce(func.sum(case((condition, _ONE), else_=_ZERO)), _ZERO)


def count_contributions(
    keys: Sequence[str],
    where: Sequence[ColumnElement[bool]],
    sign: int = 1,
    columns: Mapping[str, ColumnElement[Any]] | None = None,
    values: Mapping[str, str] = COUNT_VALUES,
) -> Select[Any]:
    """Per ``keys`` (of :data:`BUCKET` and :data:`LIMITS`, or of ``columns``: another
    ``day``): the columns of ``report_counts`` (``values`` of them) over the runs
    ``where`` selects, sums times ``sign``. The earlier run of each moving range is
    joined only when ``values`` asks for moving ranges."""
    previous = aliased(Run, name="previous")
    passed = Run.verdict == _PASS
    sums: dict[str, ColumnElement[Any]] = {
        "runs": func.count(),
        "runs_passed": _count_if(passed),
        "duration_ms": func.sum(duration_ms(Run.started_at, Run.finished_at)),
        "poses": func.sum(RunFacts.poses),
        "line_units": _count_if(RunFacts.line_first),
        "line_first_pass": _count_if(and_(RunFacts.line_first, passed)),
        "line_final_pass": _count_if(RunFacts.line_final_pass),
        "retests": _count_if(and_(RunFacts.attempt, ~RunFacts.line_first)),
        "aborts": _count_if(~RunFacts.attempt),
        "charted": func.count(Run.offset_x),
        **{
            f"mr_{name}": func.coalesce(
                func.sum(func.abs(getattr(Run, name) - getattr(previous, name))), _inline(0.0)
            )
            for name in COEFFICIENTS
        },
    }
    totals = {
        **{name: (value * _inline(sign) if sign != 1 else value) for name, value in sums.items()},
        "first_start": func.min(Run.started_at),
        "last_finish": func.max(Run.finished_at),
    }
    picked = _keys(keys, dict(columns or {}))
    stmt = (
        select(*picked, *(totals[name].label(name) for name in values))
        .select_from(Run)
        .join(RunFacts, RunFacts.run_pk == Run.id)
    )
    if any(name.startswith("mr_") for name in values):
        stmt = stmt.outerjoin(previous, previous.id == RunFacts.chart_previous)
    return stmt.where(*where).group_by(*picked)


def failure_contributions(keys: Sequence[str], where: Sequence[ColumnElement[bool]]) -> Select[Any]:
    """Per ``keys`` (of :data:`BUCKET` and ``code``): failing runs by first reason."""
    picked = _keys(keys, {"code": RunFacts.first_failure})
    return (
        select(*picked, func.count().label("runs"))
        .select_from(Run)
        .join(RunFacts, RunFacts.run_pk == Run.id)
        .where(Run.verdict == _FAIL, RunFacts.first_failure.is_not(None), *where)
        .group_by(*picked)
    )


def _limits_of(specs: Sequence[ParameterSpec], bounds: FamilyBounds) -> FromClause:
    """One row per parameter: its limits, marginal zones, histogram range and centre."""
    limits: list[Select[Any]] = []
    for spec in specs:
        lower, upper = bounds[spec.family]
        start, width, bins = histogram_bins(lower, upper)
        zone_low, zone_high = marginal_zones(lower, upper)
        low, high = tolerance(lower, upper)
        numbers = {
            "lower": lower,
            "upper": upper,
            "zone_low": None if lower is None else zone_low,
            "zone_high": None if upper is None else zone_high,
            "start": start,
            "width": width,
            "end": start + width * bins,
            "centre": (low + high) / 2,
        }
        columns: list[ColumnElement[Any]] = [_inline(spec.name).label("parameter")]
        columns += [
            cast(_inline(None if v is None else float(v)), Double()).label(k)
            for k, v in numbers.items()
        ]
        limits.append(select(*columns))
    return union_all(*limits).subquery("limits")


def parameter_contributions(
    keys: Sequence[str],
    where: Sequence[ColumnElement[bool]],
    bounds: FamilyBounds,
    columns: Mapping[str, ColumnElement[Any]] | None = None,
    *,
    moments_only: bool = False,
) -> list[Select[Any]]:
    """Per parameter and ``keys`` (of :data:`BUCKET`, or of ``columns``: another
    ``day``): the columns of ``report_parameters`` over the runs ``where`` selects,
    against ``bounds`` (``moments_only``: only :data:`MOMENT_VALUES`, for a trend's Cpk,
    by :func:`_moments`).

    ``c`` is the centre of the tolerance, bins those of
    :func:`station.domain.quality.capability.histogram_bins`, marginal and out-of-limits as
    :func:`station.domain.quality.capability.marginal_zones` says. One scan of the runs (with
    their facts) for the per-run parameters, one of their poses for pose noise, each
    paired with the parameters' limits.
    """
    if moments_only:
        return [_moments(keys, where, bounds, columns)]
    selects = []
    runs = Run.__table__.join(RunFacts.__table__, RunFacts.run_pk == Run.id)
    poses = RunPose.__table__.join(Run.__table__, OWN_POSES)
    for rows, stored in ((runs, PER_RUN), (poses, PER_POSE)):
        specs = [spec for spec in PARAMETERS if spec.name in stored]
        limits = _limits_of(specs, bounds)
        value = case(
            *((limits.c.parameter == _inline(spec.name), stored[spec.name]) for spec in specs)
        )
        bins = len(HISTOGRAM)
        # OFFSET 0: PostgreSQL keeps value and bin columns instead of inlining their
        # expressions into every aggregate.
        v = (
            select(
                limits,
                *_keys(keys, dict(columns or {})),
                value.label("x"),
                case(
                    (value < limits.c.start, _ZERO),
                    (value >= limits.c.end, _inline(bins - 1)),
                    else_=cast(func.floor((value - limits.c.start) / limits.c.width), Integer),
                ).label("bin"),
            )
            .select_from(rows)
            .join(limits, true())
            .where(value.is_not(None), *where)
            .offset(0)
            .subquery("v")
        )
        x, c = v.c.x, v.c
        outside = or_(
            and_(c.lower.is_not(None), x < c.lower), and_(c.upper.is_not(None), x > c.upper)
        )
        near = or_(
            and_(c.zone_low.is_not(None), x < c.zone_low),
            and_(c.zone_high.is_not(None), x > c.zone_high),
        )
        deviation = x - c.centre
        grouped = [c.parameter, *(c[name] for name in keys)]
        selects.append(
            select(
                *grouped,
                func.count(x).label("n"),
                func.sum(deviation).label("sum"),
                func.sum(deviation * deviation).label("squares"),
                func.min(x).label("min"),
                func.max(x).label("max"),
                _count_if(outside).label("outside"),
                _count_if(and_(~outside, near)).label("marginal"),
                *(_count_if(c.bin == _inline(i)).label(h) for i, h in enumerate(HISTOGRAM)),
            ).group_by(*grouped)
        )
    return selects


def _moments(
    keys: Sequence[str],
    where: Sequence[ColumnElement[bool]],
    bounds: FamilyBounds,
    columns: Mapping[str, ColumnElement[Any]] | None,
) -> Select[Any]:
    """n, Σ(x − c) and Σ(x − c)² of every parameter per ``keys``, as rows of
    ``parameter``, keys, ``n``, ``sum``, ``squares``.

    Performance (the report page in a plant time zone or with shifts, where the trend
    reads the runs of up to 31 days; docs/benchmarks.md "report"): one scan of the runs
    and their facts, aggregated into one wide row per group with a column triple per
    parameter, instead of pairing every run with every parameter as the full
    contributions do; the per-pose parameters come from the run's sums over its poses
    (``run_facts.noise_*``, Σx and Σx²: Σ(x − c) = Σx − cn, Σ(x − c)² = Σx² − 2cΣx + c²n),
    not from its every pose. The few wide rows are then turned into one row per parameter.
    """
    picked = _keys(keys, dict(columns or {}))
    sums: list[ColumnElement[Any]] = []
    for spec in PARAMETERS:
        low, high = tolerance(*bounds[spec.family])
        c = _inline((low + high) / 2)
        moments: tuple[ColumnElement[Any], ColumnElement[Any], ColumnElement[Any]]
        if spec.name in PER_RUN:
            deviation = PER_RUN[spec.name] - c
            moments = (
                func.count(PER_RUN[spec.name]),
                func.sum(deviation),
                func.sum(deviation * deviation),
            )
        else:
            axis = spec.name.removeprefix("pose_noise_")
            x = func.sum(getattr(RunFacts, f"noise_sum_{axis}"))
            x2 = func.sum(getattr(RunFacts, f"noise_squares_{axis}"))
            count = func.sum(RunFacts.poses)
            moments = (count, x - c * count, x2 - _inline(2.0) * c * x + c * c * count)
        sums += [
            moment.label(f"{prefix}_{spec.name}")
            for prefix, moment in zip("nsq", moments, strict=True)
        ]
    runs = Run.__table__.join(RunFacts.__table__, RunFacts.run_pk == Run.id)
    wide = select(*picked, *sums).select_from(runs).where(*where).group_by(*picked).subquery("wide")
    names = union_all(*(select(_inline(spec.name).label("parameter")) for spec in PARAMETERS))
    parameter = names.subquery("names").c.parameter

    def pick(prefix: str) -> ColumnElement[Any]:
        return case(
            *(
                (parameter == _inline(spec.name), wide.c[f"{prefix}_{spec.name}"])
                for spec in PARAMETERS
            )
        )

    counted = pick("n")
    return (
        select(
            parameter.label("parameter"),
            *(wide.c[name] for name in keys),
            counted.label("n"),
            pick("s").label("sum"),
            pick("q").label("squares"),
        )
        .select_from(wide.join(parameter.table, true()))
        .where(counted > _ZERO)
    )


# -- keeping the roll-ups -----------------------------------------------------------------


#: Each roll-up's key columns and how each of its value columns merges.
_ROLLUPS: dict[Any, tuple[Sequence[str], Mapping[str, str]]] = {
    ReportCounts: (COUNT_KEYS, COUNT_VALUES),
    ReportFailures: (FAILURE_KEYS, FAILURE_VALUES),
    ReportParameters: (("parameter", *BUCKET), PARAMETER_VALUES),
}


def _upsert(dialect: str, table: Any, rows: Select[Any]) -> Executable:
    """Add ``rows`` into the roll-up ``table``: sums added, minima and maxima kept."""
    keys, values = _ROLLUPS[table]
    stmt = (postgresql.insert if dialect == "postgresql" else sqlite.insert)(table)
    stmt = stmt.from_select([*keys, *values], rows)
    current, added = table.__table__.c, stmt.excluded
    merges = {"sum": lambda a, b: a + b, "min": smaller, "max": larger}
    merged = {name: merges[merge](current[name], added[name]) for name, merge in values.items()}
    return stmt.on_conflict_do_update(index_elements=list(keys), set_=merged)


def stored_bounds(connection: Connection) -> FamilyBounds:
    """The bounds ``report_parameters`` was counted with (empty before any)."""
    rows = connection.execute(select(ReportBounds.family, ReportBounds.lower, ReportBounds.upper))
    return {family: (lower, upper) for family, lower, upper in rows}


def _bounds_for_rollup(connection: Connection, run_pk: int) -> FamilyBounds | None:
    """The stored bounds (empty: the run's profile is not stored either, nothing is binned
    yet); before any, the bounds of the run's stored profile, with every stored run,
    ``run_pk`` too, counted against them now by :func:`rebuild` (``None``)."""
    bounds = stored_bounds(connection)
    if bounds:
        return bounds
    profile = _profile_bounds(connection, Run.id == run_pk)
    if profile is not None:
        rebuild(connection, profile)
        return None
    return {}


def _profile_bounds(connection: Connection, *where: ColumnElement[bool]) -> FamilyBounds | None:
    """The bounds of the stored profile of the latest run ``where`` selects that has one."""
    document = connection.execute(
        select(StoredLimitsProfile.document)
        .join(Run, Run.limits_sha256 == StoredLimitsProfile.sha256)
        .where(*where)
        .order_by(Run.started_at.desc(), Run.id.desc())
        .limit(1)
    ).scalar_one_or_none()
    return None if document is None else profile_bounds(LimitsProfile.model_validate_json(document))


def lock_submissions(connection: Connection) -> None:
    """Serialise submissions: each one derives facts from every run stored before it.

    PostgreSQL: a transaction-scoped advisory lock. Advisory locks span the whole
    database, so the key names the schema of the ``runs`` table the statements reach
    (resolved as they resolve it): installations that share one database in schemas of
    their own do not wait for each other's submissions. In the ``public`` schema the key
    is the one earlier versions took, so servers of both versions on one database, as
    while a plant upgrades them one by one, still take turns. SQLite serialises writers
    already.
    """
    if connection.dialect.name == "postgresql":
        connection.execute(text(_LOCK_SUBMISSIONS))


#: The lock of :func:`lock_submissions`: one row, the schema of ``runs`` keying it.
_LOCK_SUBMISSIONS = """
SELECT pg_advisory_xact_lock(hashtext(
    CASE n.nspname WHEN 'public' THEN 'calstation.runs' ELSE n.nspname || '.calstation.runs' END
))
FROM pg_class AS c JOIN pg_namespace AS n ON n.oid = c.relnamespace
WHERE c.oid = 'runs'::regclass
"""


@dataclass(frozen=True)
class _Submission:
    """The statements of :func:`record_run`, built once per dialect and bounds.

    Bound parameters: ``run_pk``, ``serial`` and ``started_at`` of the new run;
    ``changed`` the stored runs whose facts it may change; ``both`` those and the new run.
    """

    changed: Executable
    take_out: Executable
    forget: Executable
    facts: Executable
    counts: Executable
    failures: Executable
    #: ``None`` before any bounds: nothing to bin against.
    parameters: Executable | None


@cache
def _submission(
    dialect: str, bounds: tuple[tuple[str, tuple[float | None, float | None]], ...]
) -> _Submission:
    run_pk = bindparam("run_pk", type_=Run.id.type)
    changed: BindParameter[int] = bindparam("changed", expanding=True)
    both: BindParameter[int] = bindparam("both", expanding=True)
    # The new run's start and serial as values, so both walk their index.
    started_at = bindparam("started_at", type_=Run.started_at.type)
    after_this = tuple_(Run.started_at, Run.id) > tuple_(started_at, run_pk)
    following = (
        select(Run.id)
        .where(Run.offset_x.is_not(None), Run.purpose.is_(None), after_this)
        .order_by(Run.started_at, Run.id)
        .limit(1)
        .subquery("following")
    )
    same_unit = select(Run.id).where(Run.serial == bindparam("serial", type_=Run.serial.type))
    new = [Run.id == run_pk]
    parameters = None
    if bounds:
        rows = union_all(*parameter_contributions(BUCKET, new, dict(bounds))).subquery("parameters")
        parameters = _upsert(
            dialect,
            ReportParameters,
            # WHERE: SQLite reads an ON after a bare FROM as a join's.
            select(*rows.c).where(true()),
        )
    return _Submission(
        changed=union(same_unit, select(following.c.id)),
        take_out=_upsert(
            dialect, ReportCounts, count_contributions(COUNT_KEYS, [Run.id.in_(changed)], -1)
        ),
        forget=delete(RunFacts).where(RunFacts.run_pk.in_(changed)),
        facts=insert(RunFacts).from_select(_FACT_COLUMNS, _facts([Run.id.in_(both)])),
        counts=_upsert(dialect, ReportCounts, count_contributions(COUNT_KEYS, [Run.id.in_(both)])),
        failures=_upsert(dialect, ReportFailures, failure_contributions(FAILURE_KEYS, new)),
        parameters=parameters,
    )


def record_run(connection: Connection, run_pk: int) -> None:
    """Bring the facts and roll-ups up to date with the newly stored run ``run_pk``.

    The runs whose facts it may change, its unit's other runs and the next run of the
    line with coefficients, are taken out of ``report_counts``, their facts recomputed,
    and added back with the new run.
    """
    purpose, serial, started_at = connection.execute(
        select(Run.purpose, Run.serial, Run.started_at).where(Run.id == run_pk)
    ).one()
    bounds = None if purpose is not None else _bounds_for_rollup(connection, run_pk)
    if bounds is None:
        return
    do = _submission(connection.dialect.name, tuple(sorted(bounds.items())))
    found = connection.scalars(
        do.changed, {"run_pk": run_pk, "serial": serial, "started_at": started_at}
    )
    changed = sorted(set(found) - {run_pk})
    if changed:
        connection.execute(do.take_out, {"changed": changed})
        connection.execute(do.forget, {"changed": changed})
    connection.execute(do.facts, {"both": [*changed, run_pk]})
    connection.execute(do.counts, {"both": [*changed, run_pk]})
    connection.execute(do.failures, {"run_pk": run_pk})
    if do.parameters is not None:
        connection.execute(do.parameters, {"run_pk": run_pk})


def rebuild(connection: Connection, bounds: FamilyBounds | None = None) -> None:
    """Recompute every fact and roll-up from the raw tables, in SQL.

    Parameters are binned against ``bounds`` (default: the stored limits profile of the
    latest run that has one), which are stored in ``report_bounds``; with neither, no
    parameter is binned (until a run brings a profile: :func:`record_run`).
    """
    bounds = bounds or _profile_bounds(connection)
    for table in (ReportParameters, ReportFailures, ReportCounts, RunFacts, ReportBounds):
        connection.execute(delete(table))
    if bounds is not None:
        connection.execute(
            insert(ReportBounds),
            [{"family": f, "lower": lo, "upper": up} for f, (lo, up) in bounds.items()],
        )
    connection.execute(insert(RunFacts).from_select(_FACT_COLUMNS, _facts([PRODUCTION])))
    rolled = parameter_contributions(BUCKET, [PRODUCTION], bounds) if bounds is not None else []
    for rollup, rows in (
        (ReportCounts, count_contributions(COUNT_KEYS, [PRODUCTION])),
        (ReportFailures, failure_contributions(FAILURE_KEYS, [PRODUCTION])),
        *((ReportParameters, parameters) for parameters in rolled),
    ):
        keys, values = _ROLLUPS[rollup]
        connection.execute(insert(rollup).from_select([*keys, *values], rows))
