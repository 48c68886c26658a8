"""Engine and session factory of the results database."""

from pathlib import Path
from typing import Any

from sqlalchemy import Connection, Engine, create_engine, event, make_url
from sqlalchemy.orm import Session, sessionmaker

from db import migrate
from db.settings import DatabaseSettings


def _sqlite_connect(dbapi_connection: Any, _record: Any) -> None:
    # The sqlite3 module's own transaction handling breaks SAVEPOINT and transactional
    # DDL; leave it in autocommit and let SQLAlchemy emit BEGIN (see _sqlite_begin).
    dbapi_connection.isolation_level = None
    cursor = dbapi_connection.cursor()
    cursor.execute("PRAGMA foreign_keys=ON")
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute("PRAGMA busy_timeout=10000")
    cursor.close()


def _sqlite_begin(connection: Connection) -> None:
    connection.exec_driver_sql("BEGIN")


def make_engine(url: str, **kwargs: Any) -> Engine:
    """An engine for ``url``; SQLite files get foreign keys, WAL and a busy timeout."""
    parsed = make_url(url)
    if parsed.get_backend_name() == "sqlite":
        if parsed.database and parsed.database != ":memory:":
            Path(parsed.database).expanduser().parent.mkdir(parents=True, exist_ok=True)
        engine = create_engine(parsed, **kwargs)
        event.listen(engine, "connect", _sqlite_connect)
        event.listen(engine, "begin", _sqlite_begin)
        return engine
    kwargs.setdefault("pool_pre_ping", True)
    return create_engine(parsed, **kwargs)


class Database:
    """One results database: its engine and a factory of sessions."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        self.sessions = sessionmaker(engine, expire_on_commit=False)

    @property
    def is_sqlite(self) -> bool:
        """Whether this is the embedded (SQLite) database."""
        return self.engine.dialect.name == "sqlite"

    def session(self) -> Session:
        """A new session (use it as a context manager)."""
        return self.sessions()

    def dispose(self) -> None:
        """Close every pooled connection."""
        self.engine.dispose()


def open_database(url: str | None = None, *, auto_migrate: bool | None = None) -> Database:
    """Open the results database at ``url`` (default: from :class:`DatabaseSettings`).

    A SQLite database is created and migrated to the latest schema on first use, so the
    embedded default needs no set-up. A server database is migrated explicitly
    (``calstation db upgrade``); opening one whose schema is behind raises
    :class:`db.migrate.SchemaOutOfDateError`.
    """
    engine = make_engine(url or DatabaseSettings().url())
    database = Database(engine)
    try:
        if auto_migrate if auto_migrate is not None else database.is_sqlite:
            migrate.upgrade(engine)
        else:
            migrate.require_current(engine)
    except BaseException:
        database.dispose()
        raise
    return database
