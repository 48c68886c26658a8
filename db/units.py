"""Each unit's current calibration, kept ready to serve in the ``units`` table.

``GET /api/v1/units/{serial}`` is the plant's most frequent question. Its answer, the
JSON of :class:`station.records.UnitCalibration` for the unit's latest run, is written
when a run is stored (:func:`record_latest`, in the submission's transaction) and read
back as text by primary key (:class:`UnitLookups`): no ORM, no validation and no
serialisation on the read path, and one statement for all the lookups that arrive
while the previous one is out.

"Latest" is the order of ``ix_runs_serial_started_at``: ``(started_at, id)``. A run
delivered late by a station's outbox, older than the unit's latest, leaves the row as it
is; concurrent submissions for one unit are ordered by the row lock of the upsert.
"""

import asyncio
from collections.abc import Sequence
from typing import Any

from sqlalchemy import Select, bindparam, func, select, tuple_
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.ext.asyncio import AsyncEngine
from sqlalchemy.orm import Session

from db.engine import for_dialect
from db.models import Run, Unit
from station.records import RunSummary, StoredRun, UnitCalibration


def _latest_wins(dialect: Any) -> Any:
    """``INSERT … ON CONFLICT (serial) DO UPDATE`` unless the stored run is later.

    The same run is written again: that is how :meth:`db.RunRepository.refresh_units`
    rewrites the stored answers.
    """
    stmt = dialect.insert(Unit)
    new = stmt.excluded
    return stmt.on_conflict_do_update(
        index_elements=[Unit.serial],
        set_={"run_pk": new.run_pk, "started_at": new.started_at, "calibration": new.calibration},
        where=tuple_(Unit.started_at, Unit.run_pk) <= tuple_(new.started_at, new.run_pk),
    )


# Built once, values bound at execution: the compiled statement is cached.
_UPSERT = {"postgresql": _latest_wins(postgresql), "sqlite": _latest_wins(sqlite)}

_CURRENT: Select[str, str] = select(Unit.serial, Unit.calibration).where(
    Unit.serial.in_(bindparam("serials", expanding=True))
)


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
    session.execute(for_dialect(session, _UPSERT), [_row(pk, run) for pk, run in runs])


def latest_run_pks(session: Session) -> list[int]:
    """The latest run of every unit, from ``runs`` alone (one windowed scan)."""
    ranked = select(
        Run.id,
        func.row_number()
        .over(partition_by=Run.serial, order_by=(Run.started_at.desc(), Run.id.desc()))
        .label("nth"),
    ).subquery()
    return list(session.scalars(select(ranked.c.id).where(ranked.c.nth == 1)))


class UnitLookups:
    """Answers unit lookups, batching the concurrent ones into one statement.

    A lookup starts a statement at once while fewer than ``readers`` are out. Lookups
    that arrive while all are out wait for the next one to return, which then asks for
    all of them together (at most ``batch`` serial numbers): under load a round trip
    to the database serves many requests, at low load none waits for another.
    """

    def __init__(self, engine: AsyncEngine, readers: int = 1, batch: int = 200) -> None:
        self.engine = engine
        self.readers = readers
        self.batch = batch
        self._waiting: dict[str, list[asyncio.Future[str | None]]] = {}
        self._out = 0  # readers running
        self._tasks: set[asyncio.Task[None]] = set()  # referenced until done

    async def get(self, serial: str) -> str | None:
        """The stored answer about ``serial`` (JSON text), or ``None`` for an unknown unit."""
        answer: asyncio.Future[str | None] = asyncio.get_running_loop().create_future()
        self._waiting.setdefault(serial, []).append(answer)
        if self._out < self.readers:
            self._out += 1
            reader = asyncio.create_task(self._read())
            self._tasks.add(reader)
            reader.add_done_callback(self._tasks.discard)
        return await answer

    async def _read(self) -> None:
        try:
            while self._waiting:
                serials = list(self._waiting)[: self.batch]
                waiting = {serial: self._waiting.pop(serial) for serial in serials}
                try:
                    async with self.engine.connect() as connection:
                        result = await connection.execute(_CURRENT, {"serials": serials})
                        found = {serial: calibration for serial, calibration in result}
                except Exception as exc:  # each waiting request fails with the database
                    _settle(waiting, exc)
                else:
                    _settle(waiting, found)
        finally:
            # Counted out in the same step as the last look at the queue: a lookup
            # queued after it finds a free reader slot.
            self._out -= 1


def _settle(
    waiting: dict[str, list["asyncio.Future[str | None]"]], found: dict[str, str] | Exception
) -> None:
    """Give each waiting lookup its answer, or the error that prevented it."""
    for serial, answers in waiting.items():
        for answer in answers:
            if answer.done():  # its request was cancelled: the client went away
                continue
            if isinstance(found, Exception):
                answer.set_exception(found)
            else:
                answer.set_result(found.get(serial))
