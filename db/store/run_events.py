"""Runs in the order the results database stored them, for the line's event stream.

``runs.id`` grows with every stored run, and submissions are serialised
(:func:`db.rollups.lock_submissions`): a run with a higher id is committed after every
run with a lower one, so a reader that remembers the last id it saw and asks for the
runs after it misses none and sees none twice (``GET /api/v1/events``, :mod:`api.routes.events`).
Each read is one primary-key range scan.
"""

from typing import Any

from sqlalchemy import Row, and_, func, select
from sqlalchemy.orm import Session

from db.models import Run, RunFailure


def last_stored(session: Session) -> int:
    """The id of the latest stored run (0 for none)."""
    return session.scalar(select(func.max(Run.id))) or 0


def stored_after(session: Session, after: int, limit: int) -> list[Row[Any]]:
    """Up to ``limit`` runs stored after the run with id ``after``, in the order stored:
    id, run_id, serial, station_id, operator_id, lot, started_at, finished_at, verdict,
    disposition and ``failure``, the code of its first failure reason."""
    columns: list[Any] = [
        Run.id,
        Run.run_id,
        Run.serial,
        Run.station_id,
        Run.operator_id,
        Run.lot,
        Run.started_at,
        Run.finished_at,
        Run.verdict,
        Run.disposition,
        RunFailure.code.label("failure"),
    ]
    stmt = (
        select(*columns)
        .outerjoin(RunFailure, and_(RunFailure.run_pk == Run.id, RunFailure.position == 0))
        .where(Run.id > after)
        .order_by(Run.id)
        .limit(limit)
    )
    return list(session.execute(stmt).all())
