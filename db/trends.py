"""The report's trend: per plant day, units, first-pass and final yield, and Cpk.

The days are the plant's (:mod:`station.quality.days`). In UTC they are the roll-ups'
days, and :class:`db.reports.ReportQueries` adds up the roll-ups as for the rest of the
report; in another zone a day starts at a local midnight that cuts the roll-ups' days,
so each run is numbered with its plant day (:func:`day_key`, a ``CASE`` over the days'
starts) and the runs of the trend's days are aggregated instead (at most
:data:`TREND_DAYS` of them). Units count on the day of their first run on the line, as
in the summary, so the days' units add up to the summary's over the same runs.
"""

from collections.abc import Mapping, Sequence
from datetime import date, timedelta
from typing import Any

from sqlalchemy import ColumnElement, Integer, Row, RowMapping, case, literal

from db.models import Run
from station.quality.capability import cpk, shifted_moments, tolerance
from station.quality.days import day_number, midnight
from station.quality.figures import TrendDay
from station.quality.parameters import PARAMETERS, FamilyBounds

#: The most days a trend shows: the latest of the range.
TREND_DAYS = 31


def day_key(days: Sequence[date], zone: str) -> ColumnElement[int]:
    """Each run's plant day number, for runs from the first of ``days`` to the end of
    the last."""
    starts = [(midnight(day + timedelta(days=1), zone), day_number(day)) for day in days[:-1]]
    last = literal(day_number(days[-1]), Integer())
    if not starts:
        return last
    return case(*((Run.started_at < end, literal(n, Integer())) for end, n in starts), else_=last)


def _ratio(part: int, whole: int) -> float | None:
    return part / whole if whole else None


def _cpk(row: RowMapping, bounds: FamilyBounds, family: str) -> float | None:
    lower, upper = bounds[family]
    low, high = tolerance(lower, upper)
    mean, std = shifted_moments(
        int(row["n"]), float(row["sum"]), float(row["squares"]), (low + high) / 2
    )
    return cpk(mean, std, lower, upper)


def trend_days(
    days: Sequence[date],
    counts: Sequence[Row[Any]],
    parameters: Sequence[Row[Any]],
    bounds: FamilyBounds | None,
) -> list[TrendDay]:
    """The trend over ``days`` from the per-day rows of ``report_counts`` and
    ``report_parameters`` sums (days without runs show zeros)."""
    by_day: Mapping[int, RowMapping] = {int(r.day): r._mapping for r in counts}
    stats: dict[tuple[int, str], RowMapping] = {
        (int(r.day), r.parameter): r._mapping for r in parameters
    }
    trend = []
    for day in days:
        n = day_number(day)
        row = by_day.get(n)
        runs, passed, units, first, final = (
            (0, 0, 0, 0, 0)
            if row is None
            else (
                int(row["runs"]),
                int(row["runs_passed"]),
                int(row["line_units"]),
                int(row["line_first_pass"]),
                int(row["line_final_pass"]),
            )
        )
        trend.append(
            TrendDay(
                day=day,
                runs=runs,
                runs_passed=passed,
                units=units,
                first_pass_yield=_ratio(first, units),
                final_yield=_ratio(final, units),
                run_yield=_ratio(passed, runs),
                cpk={
                    spec.name: (
                        _cpk(stats[(n, spec.name)], bounds, spec.family)
                        if bounds is not None and (n, spec.name) in stats
                        else None
                    )
                    for spec in PARAMETERS
                },
            )
        )
    return trend
