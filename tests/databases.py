"""Database fixtures (a pytest plugin loaded by tests/conftest.py): SQLite and PostgreSQL.

Every database test runs on both backends (``database_url`` is parametrised). The
PostgreSQL URL comes from ``CALSTATION_TEST_POSTGRES_URL``; each test session works in a
schema of its own (other sessions may share the database) and drops it at the end.
Tests are isolated from each other: ``session`` rolls back an outer transaction,
``database`` empties every table after the test.
"""

import os
import secrets
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import psycopg
import pytest
from sqlalchemy import Connection, make_url, text
from sqlalchemy.orm import Session

from db import Database, make_engine, open_database
from db.base import Base

POSTGRES_ENV = "CALSTATION_TEST_POSTGRES_URL"


def postgres_server_url() -> str:
    url = os.environ.get(POSTGRES_ENV)
    if not url:
        pytest.skip(
            f"PostgreSQL tests need {POSTGRES_ENV} (e.g. postgresql+psycopg://postgres@127.0.0.1:5432/test)"
        )
    try:
        dsn = make_url(url).set(drivername="postgresql").render_as_string(hide_password=False)
        psycopg.connect(dsn, connect_timeout=3).close()
    except psycopg.OperationalError as exc:
        pytest.skip(f"PostgreSQL at {POSTGRES_ENV} does not answer: {exc}".splitlines()[0])
    return url


@pytest.fixture(scope="session")
def postgresql_url() -> Iterator[str]:
    """A URL whose connections work in a fresh schema of the test database, dropped at the end."""
    server_url = postgres_server_url()
    schema = f"calstation_test_{os.getpid()}_{secrets.token_hex(4)}"
    admin = make_engine(server_url, isolation_level="AUTOCOMMIT")
    with admin.connect() as connection:
        connection.execute(text(f'CREATE SCHEMA "{schema}"'))
    url = make_url(server_url).update_query_dict(
        {"options": f"-csearch_path={schema} -csynchronous_commit=off"}
    )
    try:
        yield url.render_as_string(hide_password=False)
    finally:
        with admin.connect() as connection:
            connection.execute(text(f'DROP SCHEMA "{schema}" CASCADE'))
        admin.dispose()


@contextmanager
def own_postgres_database(
    prefix: str = "calstation_own", server_url: str | None = None
) -> Iterator[str]:
    """The URL of a PostgreSQL database of its own on ``server_url`` (default: the
    suite's), created empty and dropped (its connections ended) when the block ends."""
    server_url = server_url or postgres_server_url()
    name = f"{prefix}_{os.getpid()}_{secrets.token_hex(4)}"
    admin = make_engine(server_url, isolation_level="AUTOCOMMIT")
    with admin.connect() as connection:
        connection.execute(text(f'CREATE DATABASE "{name}"'))
    try:
        yield make_url(server_url).set(database=name).render_as_string(hide_password=False)
    finally:
        with admin.connect() as connection:
            connection.execute(text(f'DROP DATABASE "{name}" WITH (FORCE)'))
        admin.dispose()


@pytest.fixture
def postgres_database_url() -> Iterator[str]:
    """A URL of a PostgreSQL database of its own, created empty and dropped after the
    test: one whose connections a test may refuse (``ALLOW_CONNECTIONS false``) without
    touching any other test's database."""
    with own_postgres_database() as url:
        yield url


@pytest.fixture(scope="session")
def sqlite_url(tmp_path_factory: pytest.TempPathFactory) -> str:
    """A SQLite file for the session."""
    return f"sqlite:///{tmp_path_factory.mktemp('db') / 'calstation.sqlite3'}"


@pytest.fixture(
    scope="session",
    params=["sqlite", pytest.param("postgresql", marks=pytest.mark.postgres)],
)
def database_url(request: pytest.FixtureRequest) -> str:
    """The URL of an empty database at the latest schema, once per backend."""
    url: str = request.getfixturevalue(f"{request.param}_url")
    return url


@pytest.fixture(scope="session")
def migrated_database(database_url: str) -> Iterator[Database]:
    """The session's database, migrated to head."""
    database = open_database(database_url, auto_migrate=True)
    yield database
    database.dispose()


@pytest.fixture
def database(migrated_database: Database) -> Iterator[Database]:
    """The migrated database, emptied after the test."""
    yield migrated_database
    with migrated_database.engine.begin() as connection:
        for table in reversed(Base.metadata.sorted_tables):
            connection.execute(table.delete())


@contextmanager
def rolled_back(database: Database) -> Iterator[Session]:
    """A session whose commits are savepoints of an outer transaction rolled back at the
    end of the block (for hypothesis examples, which a function fixture cannot reset)."""
    with database.engine.connect() as connection:
        outer = connection.begin()
        with Session(bind=connection, join_transaction_mode="create_savepoint") as session:
            yield session
        outer.rollback()


@pytest.fixture
def connection(migrated_database: Database) -> Iterator[Connection]:
    """A connection inside an outer transaction that is rolled back after the test."""
    with migrated_database.engine.connect() as connection:
        outer = connection.begin()
        yield connection
        outer.rollback()


@pytest.fixture
def session(connection: Connection) -> Iterator[Session]:
    """A session whose commits are savepoints of the rolled-back outer transaction."""
    with Session(bind=connection, join_transaction_mode="create_savepoint") as session:
        yield session


@pytest.fixture(params=["sqlite", pytest.param("postgresql", marks=pytest.mark.postgres)])
def empty_url(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[str]:
    """An empty database: a new SQLite file, or a new schema next to the session's."""
    if request.param == "sqlite":
        yield f"sqlite:///{tmp_path / 'empty.sqlite3'}"
        return
    session_url = make_url(request.getfixturevalue("postgresql_url"))
    schema = f"calstation_empty_{os.getpid()}_{secrets.token_hex(4)}"
    admin = make_engine(session_url.render_as_string(False), isolation_level="AUTOCOMMIT")
    with admin.connect() as connection:
        connection.execute(text(f'CREATE SCHEMA "{schema}"'))
    try:
        url = session_url.update_query_dict({"options": f"-csearch_path={schema}"})
        yield url.render_as_string(hide_password=False)
    finally:
        with admin.connect() as connection:
            connection.execute(text(f'DROP SCHEMA "{schema}" CASCADE'))
        admin.dispose()
