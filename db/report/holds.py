"""The units on hold: units whose latest attempt failed, with what each one holds.

A unit is on hold when its latest attempt (on the line, aborts aside:
``run_facts.line_latest``, the yield definition of :mod:`db.rollups`) failed; a unit with
nothing but aborts was never attempted and is not on hold. The line dashboard lists the
latest of them, any day, with the answer ``GET /api/v1/units/{serial}`` gives
(:class:`station.domain.record.unit_state.UnitCalibration`: its attempts, where the station
sent it, and ``holds``, the coefficients of its last verified write-back), read from ``units``.

The list walks ``ix_runs_verdict_started_at`` backwards over the failing runs and stops at
``limit`` units. The count comes from the report's daily roll-ups, kept up to date at
every submission: units (each counted once, at its first attempt) less those whose latest
attempt passed, summed over every day; a sum over a few rows a day instead of a walk over every
failing run.
"""

from dataclasses import dataclass
from typing import Any

from sqlalchemy import ColumnElement, exists, func, select
from sqlalchemy.orm import Session

from db.models import HoldReview as ReviewRow
from db.models import ReportCounts, Run, RunFacts, Unit
from station.domain.record.unit_state import UnitCalibration


@dataclass(frozen=True)
class HeldUnits:
    """The latest ``units`` on hold, newest first, of ``total`` on hold."""

    units: list[UnitCalibration]
    total: int


def held_units(session: Session, limit: int) -> HeldUnits:
    """The latest ``limit`` units on hold (their latest attempt failed), and how many
    there are."""
    answers = session.scalars(
        select(Unit.calibration)
        .select_from(Run)
        .join(RunFacts, RunFacts.run_pk == Run.id)
        .join(Unit, Unit.serial == Run.serial)
        .where(Run.verdict == "fail", RunFacts.line_latest)
        .order_by(Run.started_at.desc(), Run.id.desc())
        .limit(limit)
    ).all()
    total = session.scalar(select(func.sum(ReportCounts.line_units - ReportCounts.line_final_pass)))
    return HeldUnits(
        units=[UnitCalibration.model_validate_json(answer) for answer in answers],
        total=total or 0,
    )


def unreviewed(run: Any) -> ColumnElement[bool]:
    """Whether no quality review closed the (failed) ``run`` (a :class:`Run`, or an alias
    of it): no review of that run is stored. A hold that is open."""
    return ~exists().where(ReviewRow.serial == run.serial, ReviewRow.run_id == run.run_id)
