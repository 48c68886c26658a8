"""The lock that serialises submissions (:func:`db.rollups.lock_submissions`) on PostgreSQL,
whose advisory locks span a whole database: it is keyed by the schema of the runs it
guards, and in ``public`` by the key earlier versions took."""

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
def schemas() -> Iterator[tuple[str, str, str]]:
    """Three schemas of the test database, dropped after the test: the first two hold a
    ``runs`` table each, the third none."""
    admin = make_engine(postgres_server_url(), isolation_level="AUTOCOMMIT")
    names = tuple(f"calstation_lock_{secrets.token_hex(4)}" for _ in range(3))
    with admin.connect() as connection:
        for name in names:
            connection.execute(text(f'CREATE SCHEMA "{name}"'))
        for name in names[:2]:
            connection.execute(text(f'CREATE TABLE "{name}".runs (id integer)'))
    try:
        yield names[0], names[1], names[2]
    finally:
        with admin.connect() as connection:
            for name in names:
                connection.execute(text(f'DROP SCHEMA "{name}" CASCADE'))
        admin.dispose()


def _engine(*search_path: str, url: str | None = None) -> Engine:
    path = ",".join(search_path)
    server = make_url(url or postgres_server_url())
    return make_engine(
        server.update_query_dict({"options": f"-csearch_path={path}"}).render_as_string(
            hide_password=False
        )
    )


def _wait_briefly(connection: Connection) -> None:
    """Let this transaction's lock waits end after a short time: a held lock is never
    granted, however long the wait, and a free one is granted at once."""
    connection.execute(text("SET LOCAL lock_timeout = '200ms'"))


def _refused(connection: Connection) -> bool:
    """Whether the submission lock is held by someone else (this transaction waits)."""
    _wait_briefly(connection)
    savepoint = connection.begin_nested()
    try:
        lock_submissions(connection)
    except OperationalError as error:
        savepoint.rollback()
        return isinstance(error.orig, LockNotAvailable)
    savepoint.commit()
    return False


def test_submissions_wait_for_each_other_in_one_schema_and_not_across_schemas(
    schemas: tuple[str, str, str],
) -> None:
    mine, another, empty = schemas
    engines = [_engine(mine), _engine(mine), _engine(another), _engine(empty, mine)]
    try:
        with engines[0].connect() as holder, holder.begin():
            lock_submissions(holder)
            with engines[1].connect() as same, same.begin():
                assert _refused(same)
            with engines[2].connect() as other, other.begin():
                assert not _refused(other)
            # A search path whose first schema holds no runs reaches mine: so does its key.
            with engines[3].connect() as through, through.begin():
                assert _refused(through)
        with engines[1].connect() as same, same.begin():
            assert not _refused(same)
    finally:
        for engine in engines:
            engine.dispose()


def test_in_the_public_schema_it_is_the_lock_earlier_versions_took(
    postgres_database_url: str,
) -> None:
    """A server of an earlier version (a single key, ``hashtext('calstation.runs')``) and
    one of this version on one database, as while a plant upgrades them, take turns."""
    engine = make_engine(postgres_database_url)
    try:
        with engine.begin() as connection:
            connection.execute(text("CREATE TABLE public.runs (id integer)"))
        with engine.connect() as earlier, earlier.begin():
            earlier.execute(text("SELECT pg_advisory_xact_lock(hashtext('calstation.runs'))"))
            with engine.connect() as this, this.begin():
                assert _refused(this)
        with engine.connect() as this, this.begin():
            lock_submissions(this)
            with engine.connect() as earlier, earlier.begin():
                _wait_briefly(earlier)
                with pytest.raises(OperationalError) as refused:
                    earlier.execute(
                        text("SELECT pg_advisory_xact_lock(hashtext('calstation.runs'))")
                    )
                assert isinstance(refused.value.orig, LockNotAvailable)
    finally:
        engine.dispose()
