"""The control charts' statements: over the runs ``where`` selects (a report's range,
:func:`db.report.queries.conditions`), in time order, the coefficients' individuals and moving
ranges ([Song2006] offsets and sensitivities; Montgomery's I-MR chart).
"""

from collections.abc import Iterable, Sequence
from typing import Any

from sqlalchemy import ColumnElement, Row, RowMapping, func, select, tuple_
from sqlalchemy.orm import Session, aliased

from db.models import Run, RunFacts, RunPose
from db.rollups import PER_POSE, PER_RUN
from station.domain.quality.parameters import COEFFICIENTS


def first_moving_ranges(session: Session, where: Sequence[ColumnElement[bool]]) -> Row[Any] | None:
    """The moving ranges of the first run in range with coefficients (to the run
    before the range)."""
    previous = aliased(Run, name="previous")
    stmt = (
        select(
            *(
                func.abs(getattr(Run, name) - getattr(previous, name)).label(name)
                for name in COEFFICIENTS
            )
        )
        .join(RunFacts, RunFacts.run_pk == Run.id)
        .outerjoin(previous, previous.id == RunFacts.chart_previous)
        .where(Run.offset_x.is_not(None), *where)
        .order_by(Run.started_at, Run.id)
        .limit(1)
    )
    return session.execute(stmt).one_or_none()


def chart_limits(session: Session, where: Sequence[ColumnElement[bool]]) -> Row[Any]:
    """Count, mean and mean moving range of every coefficient, in time order, over
    the runs in range (for a range narrowed by station, operator or lot)."""
    order = (Run.started_at, Run.id)
    columns = [getattr(Run, name) for name in COEFFICIENTS]
    lagged = (
        select(
            *columns,
            *(func.abs(c - func.lag(c).over(order_by=order)).label(f"mr_{c.key}") for c in columns),
        )
        .where(Run.offset_x.is_not(None), *where)
        .subquery("lagged")
    )
    return session.execute(
        select(
            func.count().label("n"),
            *(func.avg(lagged.c[name]).label(name) for name in COEFFICIENTS),
            *(func.avg(lagged.c[f"mr_{name}"]).label(f"mr_{name}") for name in COEFFICIENTS),
        )
    ).one()


def latest_chart_points(
    session: Session, where: Sequence[ColumnElement[bool]], limit: int
) -> list[Row[Any]]:
    """The latest ``limit`` runs with coefficients, oldest first, with moving ranges."""
    latest = (
        select(Run.id, Run.started_at, Run.serial, *(getattr(Run, n) for n in COEFFICIENTS))
        .where(Run.offset_x.is_not(None), *where)
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
    return list(session.execute(stmt).all())


def latest_values(
    session: Session, where: Sequence[ColumnElement[bool]], runs: int
) -> tuple[dict[str, list[float]], int]:
    """Every parameter's values over the latest ``runs`` runs in range (the histograms'
    sample: bounded, however long the range), and how many runs that is.

    One walk of ``ix_runs_started_at`` backwards for the per-run values, one read of
    those runs' poses for the per-pose ones."""
    latest = (
        select(Run.id, Run.started_at, *(column.label(name) for name, column in PER_RUN.items()))
        .join(RunFacts, RunFacts.run_pk == Run.id)
        .where(*where)
        .order_by(Run.started_at.desc(), Run.id.desc())
        .limit(runs)
    )
    rows = session.execute(latest).all()
    values: dict[str, list[float]] = {name: [] for name in [*PER_RUN, *PER_POSE]}

    def add(read: Iterable[RowMapping], names: Iterable[str]) -> None:
        for row in read:
            for name in names:
                if (value := row[name]) is not None:
                    values[name].append(float(value))

    add((row._mapping for row in rows), PER_RUN)
    if rows:
        poses = select(*(column.label(name) for name, column in PER_POSE.items())).where(
            tuple_(RunPose.run_pk, RunPose.started_at).in_([(r.id, r.started_at) for r in rows])
        )
        add(session.execute(poses).mappings(), PER_POSE)
    return values, len(rows)
