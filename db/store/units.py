"""Each unit's current calibration, kept ready to serve in the ``units`` table.

``GET /api/v1/units/{serial}`` is the plant's most frequent question. Its answer, the
JSON of :class:`station.domain.record.unit_state.UnitCalibration` (what the unit holds, its latest
attempt, its verdict), is written when a run is stored (:func:`record_unit_run`, in the
submission's transaction) and read back as text by primary key (:class:`UnitLookups`):
no ORM, no validation and no serialisation on the read path, and one statement for all
the lookups that arrive while the previous one is out.

Runs are ordered as ``ix_runs_serial_started_at`` orders them: ``(started_at, id)``. A
run later than the unit's stored latest updates the stored answer
(:meth:`UnitCalibration.then`); a run delivered late by a station's outbox takes its
place in the unit's history, and the answer is rebuilt from every run of the unit
(:func:`record_units`). Submissions are serialised (:func:`db.rollups.lock_submissions`),
so each one reads every run and answer stored before it. Answers of an older shape are
rewritten when the database is upgraded (:func:`answers_are_stale`,
:func:`refresh_answers`).
"""

import asyncio
import json
from collections import defaultdict
from collections.abc import Callable, Sequence
from typing import Any

from pydantic import ValidationError
from sqlalchemy import select
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.exc import DBAPIError
from sqlalchemy.ext.asyncio import AsyncConnection, AsyncEngine
from sqlalchemy.orm import Session

from db.engine import DatabaseUnavailableError, for_dialect
from db.models import Run, Unit
from db.store.mapping import failures_of, summary_of
from station.domain.record.records import RunSummary, StoredRun
from station.domain.record.unit_state import UnitCalibration


def _upsert(dialect: Any) -> Any:
    """``INSERT … ON CONFLICT (serial) DO UPDATE``: the answer is computed from every run."""
    stmt = dialect.insert(Unit)
    new = stmt.excluded
    return stmt.on_conflict_do_update(
        index_elements=[Unit.serial],
        set_={"run_pk": new.run_pk, "started_at": new.started_at, "calibration": new.calibration},
    )


# Built once, values bound at execution: the compiled statement is cached.
_UPSERT = {"postgresql": _upsert(postgresql), "sqlite": _upsert(sqlite)}


def answer_json(runs: Sequence[RunSummary | StoredRun]) -> str:
    """The answer about a unit whose runs are ``runs`` (oldest first)."""
    return UnitCalibration.of_history(runs).model_dump_json()


def _unit_row(run_pk: int, latest: RunSummary | StoredRun, calibration: str) -> dict[str, Any]:
    """The ``units`` row of the unit whose latest run is ``latest`` (key ``run_pk``)."""
    return {
        "serial": latest.serial,
        "run_pk": run_pk,
        "started_at": latest.started_at,
        "calibration": calibration,
    }


def _runs_of(session: Session, serials: Sequence[str]) -> dict[str, list[tuple[int, RunSummary]]]:
    """Every run of each of ``serials`` with its key, oldest first (by ``(started_at, id)``)."""
    runs = session.scalars(
        select(Run).where(Run.serial.in_(serials)).order_by(Run.serial, Run.started_at, Run.id)
    ).all()
    failures = failures_of(session, [run.id for run in runs if run.verdict == "fail"])
    by_serial: dict[str, list[tuple[int, RunSummary]]] = defaultdict(list)
    for run in runs:
        by_serial[run.serial].append((run.id, summary_of(run, failures[run.id])))
    return by_serial


def record_units(session: Session, serials: Sequence[str]) -> None:
    """Write the answers about ``serials`` from their stored runs."""
    if not serials:
        return
    rows = [
        _unit_row(*runs[-1], answer_json([run for _, run in runs]))
        for runs in _runs_of(session, serials).values()
    ]
    session.execute(for_dialect(session, _UPSERT), rows)


def record_unit_run(session: Session, run_pk: int, run: RunSummary | StoredRun) -> None:
    """Write the answer about the unit of ``run``, just stored with the key ``run_pk``.

    The answer holds the run as ``runs`` gives it back: its limits without the profile
    (stored apart, :mod:`db.store.limits_profiles`).
    """
    run = run.model_copy(update={"limits": run.limits.model_copy(update={"profile": None})})
    stored = session.execute(
        select(Unit.run_pk, Unit.started_at, Unit.calibration).where(Unit.serial == run.serial)
    ).one_or_none()
    if stored is not None and (run.started_at, run_pk) < (stored.started_at, stored.run_pk):
        record_units(session, [run.serial])  # a late run: its place is in the history
        return
    answer = (
        UnitCalibration.of_history([run])
        if stored is None
        else UnitCalibration.model_validate_json(stored.calibration).then(run)
    )
    row = _unit_row(run_pk, run, answer.model_dump_json())
    session.execute(for_dialect(session, _UPSERT), [row])


def refresh_answers(session: Session, batch: int = 500) -> int:
    """Rewrite every unit's answer from ``runs``; return the number of units."""
    serials = list(session.scalars(select(Run.serial).distinct().order_by(Run.serial)))
    for start in range(0, len(serials), batch):
        record_units(session, serials[start : start + batch])
        session.expunge_all()
    return len(serials)


def answers_are_stale(session: Session) -> bool:
    """Whether the stored answers are of an older shape than :class:`UnitCalibration`."""
    sample = session.scalars(select(Unit.calibration).limit(1)).one_or_none()
    if sample is None:
        return False
    try:
        UnitCalibration.model_validate_json(sample)
    except ValidationError:
        return True
    return False


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

    Kept for the lookup targets of ``docs/benchmarks.md`` (at least 1,000/s; p99 under
    20 ms at 1,000/s beside submissions). The plain form, one session read by primary
    key per request through the read pool as the other read routes do, answered 493
    lookups/s at 0.95 ms of server CPU each, against 2,999/s at 0.20 ms with this class
    (``benchmarks/bench_api.py --runs 100000``, the two back to back on a loaded
    machine). In one process, CPU per lookup: 400–500 µs through the pool's session,
    215–290 µs for a Core statement on a pooled connection, 11–105 µs here.
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
