"""Unit lookups: concurrent ones share a statement, each gets its own answer or error."""

import asyncio
import json
import secrets
from datetime import timedelta
from pathlib import Path

import pytest
from sqlalchemy import delete, make_url, text
from sqlalchemy.ext.asyncio import AsyncEngine

from db import (
    Database,
    DatabaseUnavailableError,
    RunRepository,
    make_async_engine,
    open_database,
)
from db.models import Run
from db.store.units import UnitLookups, answer_json
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
            expected[serial] = answer_json(repo.history(serial))
    return expected


class CountedLookups(UnitLookups):
    """Lookups that note how many serial numbers each statement asks for."""

    def __init__(self, engine: AsyncEngine, batch: int) -> None:
        super().__init__(engine, batch=batch)
        self.statements: list[int] = []

    async def _fetch(self, serials: list[str]) -> dict[str, str]:
        self.statements.append(len(serials))
        return await super()._fetch(serials)


def lookups_on(database: Database, batch: int = 5) -> CountedLookups:
    """Lookups on the database, counting their statements."""
    return CountedLookups(make_async_engine(database.engine.url), batch=batch)


async def dispose(lookups: UnitLookups) -> None:
    await lookups.close()
    await lookups.engine.dispose()


def test_concurrent_lookups_share_statements_and_get_their_own_answers(
    database: Database, stored: dict[str, str]
) -> None:
    lookups = lookups_on(database)
    asked = [*SERIALS, "PT-404", *SERIALS[:3]]  # repeats and an unknown unit

    async def main() -> list[str | None]:
        try:
            return await asyncio.gather(*(lookups.get(serial) for serial in asked))
        finally:
            await dispose(lookups)

    answers = asyncio.run(main())
    assert answers == [stored.get(serial) for serial in asked]
    # All 16 are waiting when the reader starts: 13 distinct serials, 5 per statement.
    assert lookups.statements == [5, 5, 3]


def test_a_lone_lookup_is_answered_at_once_and_again_later(
    database: Database, stored: dict[str, str]
) -> None:
    lookups = lookups_on(database)

    async def main() -> list[str | None]:
        try:
            return [await lookups.get(serial) for serial in SERIALS[:3]]
        finally:
            await dispose(lookups)

    assert asyncio.run(main()) == [stored[serial] for serial in SERIALS[:3]]
    assert lookups.statements == [1, 1, 1]


def test_a_cancelled_lookup_leaves_the_others_answered(
    database: Database, stored: dict[str, str]
) -> None:
    lookups = lookups_on(database)

    async def main() -> tuple[list[str | None], bool]:
        try:
            tasks = [asyncio.create_task(lookups.get(serial)) for serial in SERIALS[:4]]
            await asyncio.sleep(0)  # every lookup is waiting
            tasks[2].cancel()
            done = await asyncio.gather(*tasks, return_exceptions=True)
            return [a for i, a in enumerate(done) if i != 2], tasks[2].cancelled()  # type: ignore[misc]
        finally:
            await dispose(lookups)

    answers, cancelled = asyncio.run(main())
    assert cancelled
    assert answers == [stored[SERIALS[i]] for i in (0, 1, 3)]


def test_lookups_that_arrive_while_a_statement_is_out_share_the_next(
    database: Database, stored: dict[str, str]
) -> None:
    lookups = lookups_on(database, batch=200)

    async def main() -> list[str | None]:
        try:
            first = asyncio.create_task(lookups.get(SERIALS[0]))
            while not lookups.statements:  # the first statement is out
                await asyncio.sleep(0)
            rest = await asyncio.gather(*(lookups.get(serial) for serial in SERIALS[1:]))
            return [await first, *rest]
        finally:
            await dispose(lookups)

    assert asyncio.run(main()) == [stored[serial] for serial in SERIALS]
    assert lookups.statements == [1, len(SERIALS) - 1]


def test_every_waiting_lookup_gets_the_database_error_and_the_next_reconnects(
    tmp_path: Path,
) -> None:
    # A database without the results schema yet: every statement fails.
    url = f"sqlite:///{tmp_path / 'late.sqlite3'}"
    lookups = UnitLookups(make_async_engine(url))
    record = make_record(serial=SERIALS[0])

    async def main() -> tuple[list[BaseException | str | None], str | None]:
        try:
            failed = await asyncio.gather(
                *(lookups.get(serial) for serial in SERIALS[:4]), return_exceptions=True
            )
            database = open_database(url, auto_migrate=True)  # the schema arrives
            with database.session() as session, session.begin():
                RunRepository(session).submit(record)
            database.dispose()
            return failed, await lookups.get(record.serial)
        finally:
            await dispose(lookups)

    failed, answer = asyncio.run(main())
    assert len(failed) == 4
    assert all(isinstance(outcome, DatabaseUnavailableError) for outcome in failed)
    assert "no such table: units" in str(failed[0])
    assert answer is not None
    assert json.loads(answer)["latest"]["run_id"] == str(record.run_id)


@pytest.mark.postgres
def test_a_lookup_after_the_server_dropped_the_connection_reconnects(
    postgresql_url: str,
) -> None:
    database = open_database(postgresql_url, auto_migrate=True)
    record = make_record(serial="PT-RECONNECT")
    with database.session() as session, session.begin():
        RunRepository(session).submit(record)
    name = f"lookups-{secrets.token_hex(4)}"
    lookups = UnitLookups(
        make_async_engine(make_url(postgresql_url).update_query_dict({"application_name": name}))
    )

    def drop_the_lookups_connection() -> int:
        with database.engine.connect() as connection:
            return len(
                connection.execute(
                    text(
                        "SELECT pg_terminate_backend(pid) FROM pg_stat_activity"
                        " WHERE application_name = :name"
                    ),
                    {"name": name},
                ).all()
            )

    async def main() -> tuple[str | None, int, BaseException | str | None, str | None]:
        try:
            before = await lookups.get(record.serial)
            dropped = drop_the_lookups_connection()
            broken = (await asyncio.gather(lookups.get(record.serial), return_exceptions=True))[0]
            return before, dropped, broken, await lookups.get(record.serial)
        finally:
            await dispose(lookups)

    try:
        before, dropped, broken, after = asyncio.run(main())
    finally:
        with database.session() as session, session.begin():
            session.execute(delete(Run).where(Run.serial == record.serial))
        database.dispose()
    assert dropped == 1
    assert isinstance(broken, DatabaseUnavailableError)
    assert before is not None
    assert before == after
