"""The stations' outbox reports in the results database: the latest per station.

A station reports its outbox with each run it sends
(:class:`station.domain.record.outbox_report.OutboxReport`); :func:`record_outbox` keeps it
(``INSERT … ON CONFLICT DO UPDATE``, an older report never over a newer one) in the
run's transaction, and :func:`latest_outboxes` hands them to the ``[[outbox]]`` alert
rule (:mod:`db.report.alerts`).
"""

from datetime import datetime

from sqlalchemy import select
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.orm import Session

from db.engine import for_dialect
from db.models import StationOutbox
from station.domain.record.outbox_report import OutboxReport


def _upsert(statement: postgresql.Insert | sqlite.Insert) -> postgresql.Insert | sqlite.Insert:
    """``statement`` keeping the latest report: a later one replaces it, an older one not."""
    return statement.on_conflict_do_update(
        index_elements=[StationOutbox.station_id],
        set_={
            name: statement.excluded[name]
            for name in ("queued", "oldest_s", "set_aside", "reported_at")
        },
        where=StationOutbox.reported_at <= statement.excluded.reported_at,
    )


_UPSERT = {
    "postgresql": _upsert(postgresql.insert(StationOutbox)),
    "sqlite": _upsert(sqlite.insert(StationOutbox)),
}


def record_outbox(
    session: Session, station_id: str, report: OutboxReport, reported_at: datetime
) -> None:
    """Keep ``report`` as ``station_id``'s latest (unless a later one is kept already)."""
    session.execute(
        for_dialect(session, _UPSERT),
        {"station_id": station_id, "reported_at": reported_at, **report.model_dump()},
    )


def latest_outboxes(session: Session, station_id: str | None) -> list[StationOutbox]:
    """The latest report of ``station_id`` (of every station: None), by station."""
    stmt = select(StationOutbox).order_by(StationOutbox.station_id)
    if station_id is not None:
        stmt = stmt.where(StationOutbox.station_id == station_id)
    return list(session.scalars(stmt))
