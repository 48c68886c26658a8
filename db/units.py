"""Each unit's current calibration, kept ready to serve in the ``units`` table.

``GET /api/v1/units/{serial}`` is the plant's most frequent question. Its answer, the
JSON of :class:`station.records.UnitCalibration` for the unit's latest run, is written
when a run is stored (:func:`record_latest`, in the submission's transaction) and read
back as text by primary key (:func:`current_calibration`): no ORM, no validation and
no serialisation on the read path.

"Latest" is the order of ``ix_runs_serial_started_at``: ``(started_at, id)``. A run
delivered late by a station's outbox, older than the unit's latest, leaves the row as it
is; concurrent submissions for one unit are ordered by the row lock of the upsert.
"""

from collections.abc import Sequence
from typing import Any

from sqlalchemy import Select, bindparam, func, select, tuple_
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.ext.asyncio import AsyncConnection
from sqlalchemy.orm import Session

from db.models import Run, Unit
from station.errors import CalstationError
from station.records import RunSummary, StoredRun, UnitCalibration


def _latest_wins(dialect: Any) -> Any:
    """``INSERT … ON CONFLICT (serial) DO UPDATE`` only where the new run is later."""
    stmt = dialect.insert(Unit)
    new = stmt.excluded
    return stmt.on_conflict_do_update(
        index_elements=[Unit.serial],
        set_={"run_pk": new.run_pk, "started_at": new.started_at, "calibration": new.calibration},
        where=tuple_(Unit.started_at, Unit.run_pk) < tuple_(new.started_at, new.run_pk),
    )


# Built once, values bound at execution: the compiled statement is cached.
_UPSERT = {"postgresql": _latest_wins(postgresql), "sqlite": _latest_wins(sqlite)}

_CURRENT: Select[str] = select(Unit.calibration).where(Unit.serial == bindparam("serial"))


def calibration_json(latest: RunSummary | StoredRun) -> str:
    """The answer about a unit whose latest run is ``latest``."""
    return UnitCalibration.of(latest).model_dump_json()


def _row(run_pk: int, latest: RunSummary | StoredRun) -> dict[str, Any]:
    return {
        "serial": latest.serial,
        "run_pk": run_pk,
        "started_at": latest.started_at,
        "calibration": calibration_json(latest),
    }


def record_latest(
    session: Session, runs: Sequence[tuple[int, RunSummary]] | Sequence[tuple[int, StoredRun]]
) -> None:
    """Make each ``(pk, run)`` its unit's current state, unless a later run is stored."""
    if not runs:
        return
    dialect = session.get_bind().dialect.name
    if dialect not in _UPSERT:
        raise CalstationError(f"database dialect {dialect!r} is not supported")
    session.execute(_UPSERT[dialect], [_row(pk, run) for pk, run in runs])


def latest_run_pks(session: Session) -> list[int]:
    """The latest run of every unit, from ``runs`` alone (one windowed scan)."""
    ranked = select(
        Run.id,
        func.row_number()
        .over(partition_by=Run.serial, order_by=(Run.started_at.desc(), Run.id.desc()))
        .label("nth"),
    ).subquery()
    return list(session.scalars(select(ranked.c.id).where(ranked.c.nth == 1)))


async def current_calibration(connection: AsyncConnection, serial: str) -> str | None:
    """The stored answer about ``serial`` (JSON text), or ``None`` for an unknown unit."""
    calibration: str | None = await connection.scalar(_CURRENT, {"serial": serial})
    return calibration
