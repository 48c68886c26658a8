"""Derived data whose definition changed without a change of schema, rewritten at upgrade.

The unit answers (:mod:`db.units`) and the report's facts and roll-ups
(:mod:`db.rollups`) are functions of ``runs``. When this software defines them
differently from the software that wrote them (answers of an older shape; a unit's
latest run no longer an operator's abort), :func:`rewrite_if_stale` rewrites both from
``runs`` in the upgrade's transaction: ``calstation db upgrade``, or any opening of the
embedded SQLite database.
"""

from sqlalchemy import Connection
from sqlalchemy.orm import Session

from db.rollups import lock_submissions, rebuild, stored_bounds
from db.units import answers_are_stale, refresh_answers


def rewrite_if_stale(connection: Connection) -> bool:
    """Rewrite the answers and the report's roll-ups if the answers are stale."""
    session = Session(bind=connection)
    if not answers_are_stale(session):
        return False
    lock_submissions(connection)
    refresh_answers(session)
    session.flush()
    rebuild(connection, stored_bounds(connection) or None)
    return True
