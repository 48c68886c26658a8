"""Derived data, written at upgrade when it is missing or of an older definition.

The unit answers (:mod:`db.store.units`) and the report's facts and roll-ups
(:mod:`db.rollups`) are functions of ``runs``. The migrations create their tables
only; when they are empty beside stored runs (a migration just added them, or emptied
facts of an older yield definition, as 0021 did), or the answers are of an older shape,
:func:`rewrite_if_stale` writes both from ``runs`` in the upgrade's transaction:
``calstation db upgrade``, or any opening of the embedded SQLite database.
"""

from sqlalchemy import Connection, select
from sqlalchemy.orm import Session

from db.models import Run, RunFacts, Unit
from db.rollups import lock_submissions, rebuild, stored_bounds
from db.store.units import answers_are_stale, refresh_answers


def rewrite_if_stale(connection: Connection) -> bool:
    """Write the answers and the report's roll-ups if they are missing or stale."""
    session = Session(bind=connection)
    if not (_missing(session) or answers_are_stale(session)):
        return False
    lock_submissions(connection)
    refresh_answers(session)
    session.flush()
    rebuild(connection, stored_bounds(connection) or None)
    return True


def _missing(session: Session) -> bool:
    """Whether runs are stored but the answers or the roll-ups were never written."""
    if session.scalars(select(Run.id).limit(1)).first() is None:
        return False
    no_units = session.scalars(select(Unit.serial).limit(1)).first() is None
    return no_units or session.scalars(select(RunFacts.run_pk).limit(1)).first() is None
