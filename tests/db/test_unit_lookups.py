"""Unit lookups: concurrent ones share a statement, each gets its own answer or error."""

import asyncio
from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest
from sqlalchemy import event
from sqlalchemy.exc import OperationalError
from sqlalchemy.ext.asyncio import AsyncEngine

from db import Database, RunRepository, make_async_engine
from db.units import UnitLookups, calibration_json
from tests.db.records import T0, make_record

SERIALS = [f"PT-{i:06d}" for i in range(12)]


@pytest.fixture
def stored(database: Database) -> dict[str, str]:
    """Twelve units, the odd ones retested; their expected answers by serial."""
    with database.session() as session, session.begin():
        repo = RunRepository(session)
        for i, serial in enumerate(SERIALS):
            repo.submit(make_record(serial=serial, verdict="fail", started_at=T0))
            if i % 2:
                repo.submit(make_record(serial=serial, started_at=T0 + timedelta(hours=i)))
        expected = {}
        for serial in SERIALS:
            latest = repo.latest_for_serial(serial)
            assert latest is not None
            expected[serial] = calibration_json(latest)
    return expected


def lookups_on(database: Database) -> tuple[UnitLookups, list[Any]]:
    """Lookups on the database, and the list of statements they send."""
    engine = make_async_engine(database.engine.url, isolation_level="AUTOCOMMIT")
    statements: list[Any] = []
    event.listen(
        engine.sync_engine,
        "before_cursor_execute",
        lambda _conn, _cursor, _statement, parameters, *_: statements.append(parameters),
    )
    return UnitLookups(engine, readers=1, batch=5), statements


async def dispose(engine: AsyncEngine) -> None:
    await engine.dispose()


def test_concurrent_lookups_share_statements_and_get_their_own_answers(
    database: Database, stored: dict[str, str]
) -> None:
    lookups, statements = lookups_on(database)
    asked = [*SERIALS, "PT-404", *SERIALS[:3]]  # repeats and an unknown unit

    async def main() -> list[str | None]:
        try:
            return await asyncio.gather(*(lookups.get(serial) for serial in asked))
        finally:
            await dispose(lookups.engine)

    answers = asyncio.run(main())
    assert answers == [stored.get(serial) for serial in asked]
    # All 16 are waiting when the reader starts: 13 distinct serials, 5 per statement.
    assert [len(serials) for serials in statements] == [5, 5, 3]


def test_a_lone_lookup_is_answered_at_once_and_again_later(
    database: Database, stored: dict[str, str]
) -> None:
    lookups, statements = lookups_on(database)

    async def main() -> list[str | None]:
        try:
            return [await lookups.get(serial) for serial in SERIALS[:3]]
        finally:
            await dispose(lookups.engine)

    assert asyncio.run(main()) == [stored[serial] for serial in SERIALS[:3]]
    assert len(statements) == 3


def test_a_cancelled_lookup_leaves_the_others_answered(
    database: Database, stored: dict[str, str]
) -> None:
    lookups, _ = lookups_on(database)

    async def main() -> tuple[list[str | None], bool]:
        try:
            tasks = [asyncio.create_task(lookups.get(serial)) for serial in SERIALS[:4]]
            await asyncio.sleep(0)  # every lookup is waiting
            tasks[2].cancel()
            done = await asyncio.gather(*tasks, return_exceptions=True)
            return [a for i, a in enumerate(done) if i != 2], tasks[2].cancelled()  # type: ignore[misc]
        finally:
            await dispose(lookups.engine)

    answers, cancelled = asyncio.run(main())
    assert cancelled
    assert answers == [stored[SERIALS[i]] for i in (0, 1, 3)]


def test_every_waiting_lookup_gets_the_database_error(tmp_path: Path) -> None:
    # A database without the results schema: every statement fails.
    engine = make_async_engine(f"sqlite:///{tmp_path / 'empty.sqlite3'}")
    lookups = UnitLookups(engine)

    async def main() -> list[BaseException | str | None]:
        try:
            first = await asyncio.gather(
                *(lookups.get(serial) for serial in SERIALS[:4]), return_exceptions=True
            )
            again = await asyncio.gather(lookups.get(SERIALS[0]), return_exceptions=True)
            return [*first, *again]
        finally:
            await dispose(engine)

    outcomes = asyncio.run(main())
    assert len(outcomes) == 5
    assert all(isinstance(outcome, OperationalError) for outcome in outcomes)


def test_two_readers_take_turns_and_batch_what_waits(
    database: Database, stored: dict[str, str]
) -> None:
    engine = make_async_engine(database.engine.url, isolation_level="AUTOCOMMIT")
    lookups = UnitLookups(engine, readers=2, batch=4)

    async def main() -> list[str | None]:
        try:
            return await asyncio.gather(*(lookups.get(serial) for serial in SERIALS))
        finally:
            await dispose(engine)

    assert asyncio.run(main()) == [stored[serial] for serial in SERIALS]
