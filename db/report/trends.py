"""The report's trend: per plant day (and shift), units, first-pass and final yield, Cpk.

The days are the plant's (:mod:`station.domain.quality.days`). In UTC they are the
roll-ups' days, and :class:`db.report.queries.ReportQueries` adds up the roll-ups as for
the rest of the report; in another zone a day starts at a local midnight that cuts the
roll-ups' days, so each run is numbered with its plant day (:func:`day_key`, a ``CASE``
over the days' starts) and the runs of the trend's days are aggregated instead (at most
:data:`TREND_DAYS` of them). Units count on the day of their first attempt on the line
(the yield definition of :mod:`db.rollups`), as in the summary, so the days' units add
up to the summary's over the same runs. The plant's shifts
(:mod:`station.domain.quality.shifts`) cut the same days finer: each run is numbered with its
shift (:func:`shift_key`) and the runs of the trend's shifts are aggregated, in any zone.
"""

from collections import defaultdict
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass
from datetime import date, datetime, time, timedelta
from typing import Any

from sqlalchemy import ColumnElement, Integer, Row, case, literal
from sqlalchemy.orm import Session

from db.models import Run
from db.report.queries import ReportQueries
from db.rollups import MOMENT_VALUES, TREND_COUNT_VALUES
from station.domain.quality.capability import cpk, shifted_moments, tolerance
from station.domain.quality.days import day_end, day_number, is_utc, midnight, plant_days, step
from station.domain.quality.figures import ReportFilter, TrendDay, TrendShift
from station.domain.quality.parameters import PARAMETERS, FamilyBounds
from station.domain.quality.shifts import Shift, plant_shifts

#: The most days a trend shows: the latest of the range.
TREND_DAYS = 31

#: The last moment before an exclusive end.
EPSILON = timedelta(microseconds=1)


def period_key(ends: Sequence[tuple[datetime, int]], last: int) -> ColumnElement[int]:
    """Each run's period number: that of the first period whose end (UTC) comes after the
    run's start, ``last`` past them all (``ends`` in time order)."""
    tail = literal(last, Integer())
    if not ends:
        return tail
    return case(*((Run.started_at < end, literal(n, Integer())) for end, n in ends), else_=tail)


def day_key(days: Sequence[date], zone: str) -> ColumnElement[int]:
    """Each run's plant day number, for runs from the first of ``days`` to the end of
    the last."""
    ends = [(day_end(day, zone), day_number(day)) for day in days[:-1]]
    return period_key(ends, day_number(days[-1]))


def shift_key(shifts: Sequence[Shift]) -> ColumnElement[int]:
    """Each run's shift, its index in ``shifts``, for runs from the start of the first
    to the end of the last."""
    return period_key([(s.end, i) for i, s in enumerate(shifts[:-1])], len(shifts) - 1)


def ratio(part: float, whole: float) -> float | None:
    """``part / whole``; ``None`` of nothing."""
    return part / whole if whole else None


def moments(
    row: Mapping[Any, Any], lower: float | None, upper: float | None
) -> tuple[float | None, float | None]:
    """Mean and standard deviation of a parameter from its ``row`` of ``report_parameters``
    sums: n, Σ(x − c) and Σ(x − c)² about c, the centre of the tolerance [``lower``,
    ``upper``]."""
    low, high = tolerance(lower, upper)
    return shifted_moments(
        int(row["n"]), float(row["sum"]), float(row["squares"]), (low + high) / 2
    )


def _cpk(row: Mapping[Any, Any] | None, bounds: FamilyBounds | None, family: str) -> float | None:
    """The Cpk of a parameter of ``family`` from its ``row`` of sums against ``bounds``;
    ``None`` without either."""
    if row is None or bounds is None:
        return None
    lower, upper = bounds[family]
    return cpk(*moments(row, lower, upper), lower, upper)


def _added(
    rows: Sequence[Row[Any]], names: Collection[str], key: Callable[[Row[Any]], Any]
) -> dict[Any, dict[str, Any]]:
    """The columns ``names`` of ``rows`` added up per ``key(row)``."""
    added: dict[Any, dict[str, Any]] = defaultdict(lambda: dict.fromkeys(names, 0))
    for row in rows:
        into = added[key(row)]
        for name in names:
            into[name] += row._mapping[name]
    return added


@dataclass(frozen=True)
class PeriodSums:
    """The sums of ``report_counts`` and ``report_parameters`` columns per period (a day
    or a shift, by its number) and the figures of a period from them."""

    counts: Mapping[int, Mapping[Any, Any]]
    stats: Mapping[tuple[int, str], Mapping[Any, Any]]
    bounds: FamilyBounds | None

    @classmethod
    def of_rows(
        cls, counts: Sequence[Row[Any]], parameters: Sequence[Row[Any]], bounds: FamilyBounds | None
    ) -> "PeriodSums":
        """From rows numbered by their period (``day``)."""
        return cls(
            {int(r.day): r._mapping for r in counts},
            {(int(r.day), r.parameter): r._mapping for r in parameters},
            bounds,
        )

    @classmethod
    def regrouped(
        cls,
        counts: Sequence[Row[Any]],
        parameters: Sequence[Row[Any]],
        bounds: FamilyBounds | None,
        period: Callable[[int], int],
    ) -> "PeriodSums":
        """From finer rows (``day`` a finer key), added up per ``period(key)``: every
        column a trend reads is a sum."""
        return cls(
            _added(counts, TREND_COUNT_VALUES, lambda r: period(int(r.day))),
            _added(parameters, MOMENT_VALUES, lambda r: (period(int(r.day)), r.parameter)),
            bounds,
        )

    def figures(self, n: int) -> dict[str, Any]:
        """The :class:`TrendFigures` fields of period ``n`` (zeros without runs)."""
        row = self.counts.get(n, {})
        sums = {name: int(row.get(name, 0)) for name in TREND_COUNT_VALUES}
        units = sums["line_units"]
        return {
            "runs": sums["runs"],
            "runs_passed": sums["runs_passed"],
            "units": units,
            "first_pass_yield": ratio(sums["line_first_pass"], units),
            "final_yield": ratio(sums["line_final_pass"], units),
            "run_yield": ratio(sums["runs_passed"], sums["runs"]),
            "cpk": {
                spec.name: _cpk(self.stats.get((n, spec.name)), self.bounds, spec.family)
                for spec in PARAMETERS
            },
        }


def trend_days(days: Sequence[date], sums: PeriodSums) -> list[TrendDay]:
    """The trend over ``days`` from their sums by day number (days without runs show
    zeros)."""
    return [TrendDay(day=day, **sums.figures(day_number(day))) for day in days]


def trend_shifts(shifts: Sequence[Shift], sums: PeriodSums) -> list[TrendShift]:
    """The trend over ``shifts`` from their sums by index in ``shifts``."""
    return [
        TrendShift(day=s.day, shift=s.name, start=s.start, end=s.end, **sums.figures(i))
        for i, s in enumerate(shifts)
    ]


def report_trend(
    session: Session,
    filter: ReportFilter,
    counts: Sequence[Row[Any]],
    bounds: FamilyBounds | None,
    zone: str,
    shifts: Sequence[time],
) -> tuple[list[TrendDay], list[TrendShift]]:
    """The trend over the plant's days of the range (the latest :data:`TREND_DAYS`), and
    over their shifts when the plant has ``shifts`` (start times).

    In UTC the days come from the roll-ups and the shifts from a scan of their runs; in
    another zone one scan numbers each run with its day and its shift together.
    """
    if not counts:
        return [], []
    start = filter.since or min(row.first_start for row in counts)
    end = filter.until - EPSILON if filter.until else max(row.last_finish for row in counts)
    days = plant_days(start, end, zone, TREND_DAYS)
    since = midnight(days[0], zone)
    periods = plant_shifts(max(start, since), end, zone, shifts, TREND_DAYS * len(shifts))

    def sums(first: datetime, key: ColumnElement[int] | None) -> tuple[Any, Any]:
        queries = ReportQueries(
            session, filter.model_copy(update={"since": max(first, filter.since or first)})
        )
        parameters = [] if bounds is None else queries.daily_parameters(bounds, key)
        return queries.daily_counts(key), parameters

    if not periods:
        key = None if is_utc(zone) else day_key(days, zone)
        return trend_days(days, PeriodSums.of_rows(*sums(since, key), bounds)), []
    if is_utc(zone):
        by_day = PeriodSums.of_rows(*sums(since, None), bounds)
        by_shift = PeriodSums.of_rows(*sums(periods[0].start, shift_key(periods)), bounds)
    else:
        # Key (day − d₀)·S + shift over S shifts; the day before the first (d₀) holds the
        # runs of the first shift before its midnight, which no listed day shows.
        before = step(days[0], -1)
        base, width = day_number(before), len(periods)
        key = (day_key([before, *days], zone) - base) * width + shift_key(periods)
        rows = sums(min(since, periods[0].start), key)
        by_day = PeriodSums.regrouped(*rows, bounds, lambda k: k // width + base)
        by_shift = PeriodSums.regrouped(*rows, bounds, lambda k: k % width)
    return trend_days(days, by_day), trend_shifts(periods, by_shift)
