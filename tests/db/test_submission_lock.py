"""The lock that serialises submissions (:func:`db.rollups.lock_submissions`) on PostgreSQL, whose
advisory locks span a whole database: it holds per schema, the scope of the runs it guards."""

import secrets
from collections.abc import Iterator

import pytest
from psycopg.errors import LockNotAvailable
from sqlalchemy import Connection, Engine, make_url, text
from sqlalchemy.exc import OperationalError

from db import make_engine
from db.rollups import lock_submissions
from tests.databases import postgres_server_url

pytestmark = pytest.mark.postgres


@pytest.fixture
def schemas() -> Iterator[tuple[str, str]]:
    """Two empty schemas of the test database, dropped after the test."""
    admin = make_engine(postgres_server_url(), isolation_level="AUTOCOMMIT")
    names = tuple(f"calstation_lock_{secrets.token_hex(4)}" for _ in range(2))
    with admin.connect() as connection:
        for name in names:
            connection.execute(text(f'CREATE SCHEMA "{name}"'))
    try:
        yield names[0], names[1]
    finally:
        with admin.connect() as connection:
            for name in names:
                connection.execute(text(f'DROP SCHEMA "{name}" CASCADE'))
        admin.dispose()


def _engine(schema: str) -> Engine:
    url = make_url(postgres_server_url()).update_query_dict({"options": f"-csearch_path={schema}"})
    return make_engine(url.render_as_string(hide_password=False))


def _wait_briefly(connection: Connection) -> None:
    """Let this transaction's lock waits end after a short time: a held lock is never
    granted, however long the wait, and a free one is granted at once."""
    connection.execute(text("SET LOCAL lock_timeout = '200ms'"))


def test_submissions_wait_for_each_other_in_one_schema_and_not_across_schemas(
    schemas: tuple[str, str],
) -> None:
    mine, another = schemas
    engines = [_engine(mine), _engine(mine), _engine(another)]
    try:
        with engines[0].connect() as holder, holder.begin():
            lock_submissions(holder)
            with engines[1].connect() as same, same.begin():
                _wait_briefly(same)
                with pytest.raises(OperationalError) as refused:
                    lock_submissions(same)
                assert isinstance(refused.value.orig, LockNotAvailable)
            with engines[2].connect() as other, other.begin():
                _wait_briefly(other)
                lock_submissions(other)
        with engines[1].connect() as same, same.begin():
            _wait_briefly(same)
            lock_submissions(same)
    finally:
        for engine in engines:
            engine.dispose()
