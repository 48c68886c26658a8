"""The units on hold: units whose latest run failed, with what each one holds.

A unit is on hold when its latest run (on the line, aborts aside: ``run_facts.line_latest``,
the end-of-line report's own rule, :mod:`db.rollups`) failed. The line dashboard lists the
latest of them, any day, with the answer ``GET /api/v1/units/{serial}`` gives
(:class:`station.domain.unit_state.UnitCalibration`: its attempts, where the station sent it, and
``holds``, the coefficients of its last verified write-back), read from ``units``.

The list walks ``ix_runs_verdict_started_at`` backwards over the failing runs and stops at
``limit`` units. The count comes from the report's daily roll-ups, kept up to date at
every submission: units (each counted once, at its first run) less those whose latest run
passed, summed over every day; a sum over a few rows a day instead of a walk over every
failing run.
"""

from dataclasses import dataclass
from typing import Any

from sqlalchemy import ColumnElement, exists, func, select
from sqlalchemy.orm import Session

from db.models import HoldReview as ReviewRow
from db.models import ReportCounts, Run, RunFacts, RunFailure, Unit
from db.rollups import aborted
from station.domain.unit_state import ABORTED, UnitCalibration


@dataclass(frozen=True)
class HeldUnits:
    """The latest ``units`` on hold, newest first, of ``total`` on hold."""

    units: list[UnitCalibration]
    total: int


def held_units(session: Session, limit: int) -> HeldUnits:
    """The latest ``limit`` units on hold (their latest run failed), and how many there are."""
    # A unit whose runs are all aborts was never attempted: not on hold (its latest run
    # is an abort only then, for the latest run is the latest that counts).
    on_hold = (Run.verdict == "fail", RunFacts.line_latest, ~aborted(Run.id))
    answers = session.scalars(
        select(Unit.calibration)
        .select_from(Run)
        .join(RunFacts, RunFacts.run_pk == Run.id)
        .join(Unit, Unit.serial == Run.serial)
        .where(*on_hold)
        .order_by(Run.started_at.desc(), Run.id.desc())
        .limit(limit)
    ).all()
    total = session.scalar(select(func.sum(ReportCounts.line_units - ReportCounts.line_final_pass)))
    return HeldUnits(
        units=[UnitCalibration.model_validate_json(answer) for answer in answers],
        total=(total or 0) - abort_only_units(session),
    )


def abort_only_units(session: Session) -> int:
    """Units whose every run is an operator's abort (their latest run is an abort): never
    attempted, neither on hold nor shipped. Found from the aborts' failure rows
    (``ix_run_failures_code``), not from a walk over the runs."""
    stmt = (
        select(func.count(func.distinct(RunFailure.run_pk)))
        .join(RunFacts, RunFacts.run_pk == RunFailure.run_pk)
        .where(RunFailure.code == ABORTED, RunFacts.line_latest.is_(True))
    )
    return int(session.execute(stmt).scalar_one())


def unreviewed(run: Any) -> ColumnElement[bool]:
    """Whether no quality review closed the (failed) ``run`` (a :class:`Run`, or an alias
    of it): no review of that run is stored. A hold that is open."""
    return ~exists().where(ReviewRow.serial == run.serial, ReviewRow.run_id == run.run_id)
