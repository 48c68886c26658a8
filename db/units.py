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
import json
from collections.abc import Callable, Sequence
from typing import Any

from sqlalchemy import func, select, tuple_
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.exc import DBAPIError
from sqlalchemy.ext.asyncio import AsyncConnection, AsyncEngine
from sqlalchemy.orm import Session

from db.engine import DatabaseUnavailableError, for_dialect
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


#: The lookup statement of each backend and its parameters, for the driver's own
#: connection: one text for any number of serial numbers, which the server prepares once.
_LOOKUP: dict[str, tuple[str, Callable[[list[str]], tuple[Any, ...]]]] = {
    "postgresql": (
        "SELECT serial, calibration FROM units WHERE serial = ANY(%s)",
        lambda serials: (serials,),
    ),
    "sqlite": (
        "SELECT serial, calibration FROM units WHERE serial IN (SELECT value FROM json_each(?))",
        lambda serials: (json.dumps(serials),),
    ),
}


class UnitLookups:
    """Answers unit lookups, batching the concurrent ones into one statement.

    A lookup starts a statement at once if none is out. Lookups that arrive while one
    is out wait for it to return; the next statement then asks for all of them
    together (at most ``batch`` serial numbers). Under load one round trip to the
    database serves many requests; at low load none waits for another.

    The statements go straight to the database driver, on one connection that the
    lookups keep (checked out of ``engine``'s pool, in autocommit). SQLAlchemy's
    connection checkout and execution cost more CPU than the query itself: about
    0.3 ms a statement against 0.1 ms on the driver (``docs/benchmarks.md``). A
    connection that fails is dropped, and the next lookup opens another.
    """

    def __init__(self, engine: AsyncEngine, batch: int = 200) -> None:
        self.engine = engine
        self.batch = batch
        self._statement, self._parameters = for_dialect(engine, _LOOKUP)
        self._driver_error: type[Exception] = engine.dialect.loaded_dbapi.Error
        self._waiting: dict[str, list[asyncio.Future[str | None]]] = {}
        self._reader: asyncio.Task[None] | None = None  # the statement out, if any
        self._connection: AsyncConnection | None = None
        self._driver: Any = None  # the driver's connection under ``_connection``

    async def get(self, serial: str) -> str | None:
        """The stored answer about ``serial`` (JSON text), or ``None`` for an unknown unit.

        Raises :class:`DatabaseUnavailableError` when the database does not answer.
        """
        answer: asyncio.Future[str | None] = asyncio.get_running_loop().create_future()
        self._waiting.setdefault(serial, []).append(answer)
        if self._reader is None:
            self._reader = asyncio.create_task(self._read())
        return await answer

    async def close(self) -> None:
        """Give the lookups' connection back (at server shutdown)."""
        if self._connection is not None:
            await self._connection.close()
        self._connection = self._driver = None

    async def _read(self) -> None:
        try:
            while self._waiting:
                serials = list(self._waiting)[: self.batch]
                waiting = {serial: self._waiting.pop(serial) for serial in serials}
                try:
                    found = await self._fetch(serials)
                except DatabaseUnavailableError as exc:  # each waiting request fails with it
                    _settle(waiting, exc)
                else:
                    _settle(waiting, found)
        finally:
            # Cleared in the same step as the last look at the queue: a lookup queued
            # after it starts the next reader.
            self._reader = None

    async def _fetch(self, serials: list[str]) -> dict[str, str]:
        """The stored answers of those ``serials`` that are known."""
        try:
            if self._driver is None:
                self._connection = connection = await self.engine.connect()
                await connection.execution_options(isolation_level="AUTOCOMMIT")
                self._driver = (await connection.get_raw_connection()).driver_connection
            cursor = await self._driver.execute(self._statement, self._parameters(serials))
            rows = await cursor.fetchall()
            await cursor.close()
        except (DBAPIError, self._driver_error) as exc:  # opening, or the statement
            await self._drop()
            raise DatabaseUnavailableError.of(self.engine.url, exc) from exc
        return dict(rows)

    async def _drop(self) -> None:
        """Discard the connection: it is broken, or it refused the statement."""
        if self._connection is not None:
            await self._connection.invalidate()
        await self.close()


def _settle(
    waiting: dict[str, list["asyncio.Future[str | None]"]],
    found: dict[str, str] | DatabaseUnavailableError,
) -> None:
    """Give each waiting lookup its answer, or the error that prevented it."""
    for serial, answers in waiting.items():
        for answer in answers:
            if answer.done():  # its request was cancelled: the client went away
                continue
            if isinstance(found, DatabaseUnavailableError):
                answer.set_exception(found)
            else:
                answer.set_result(found.get(serial))
