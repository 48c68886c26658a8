"""Engine and session factory of the results database."""

from collections.abc import Mapping
from pathlib import Path
from typing import Any, TypeVar

from sqlalchemy import URL, Connection, Engine, create_engine, event, make_url
from sqlalchemy.ext.asyncio import AsyncEngine, create_async_engine
from sqlalchemy.orm import Session

from db.settings import check_database_url
from db.timeouts import postgres_statement_timeout, sqlite_statement_timeout
from station.domain.errors import CalstationError, InputError


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
    if connection.get_execution_options().get("isolation_level") != "AUTOCOMMIT":
        connection.exec_driver_sql("BEGIN")


def _sqlite_events(engine: Engine, *, autocommit: bool) -> None:
    event.listen(engine, "connect", _sqlite_connect)
    if not autocommit:
        event.listen(engine, "begin", _sqlite_begin)


T = TypeVar("T")


def for_dialect(bind: Session | AsyncEngine, statements: Mapping[str, T]) -> T:
    """The entry of ``statements`` for the database dialect of a session or an engine."""
    dialect = (bind.get_bind() if isinstance(bind, Session) else bind).dialect.name
    if dialect not in statements:
        raise CalstationError(f"database dialect {dialect!r} is not supported")
    return statements[dialect]


#: Async drivers of the supported backends (psycopg 3 speaks both ways).
_ASYNC_DRIVERS = {"sqlite": "sqlite+aiosqlite", "postgresql": "postgresql+psycopg"}


def make_async_engine(
    url: str | URL, *, statement_timeout_s: float | None = None, **kwargs: Any
) -> AsyncEngine:
    """An asyncio engine on the same database as :func:`make_engine` would open.

    ``statement_timeout_s`` bounds each statement of a transaction on PostgreSQL; SQLite's
    asyncio driver runs statements in a thread of its own, out of reach of :mod:`db.timeouts`.
    """
    parsed = make_url(url)
    backend = parsed.get_backend_name()
    if backend not in _ASYNC_DRIVERS:
        raise CalstationError(f"database dialect {backend!r} is not supported")
    engine = create_async_engine(parsed.set(drivername=_ASYNC_DRIVERS[backend]), **kwargs)
    if statement_timeout_s is not None and backend == "postgresql":
        postgres_statement_timeout(engine.sync_engine, statement_timeout_s)
    if backend == "sqlite":
        _sqlite_events(engine.sync_engine, autocommit=kwargs.get("isolation_level") == "AUTOCOMMIT")
    return engine


def make_engine(
    url: str | URL, *, statement_timeout_s: float | None = None, **kwargs: Any
) -> Engine:
    """An engine for ``url``; SQLite files get foreign keys, WAL and a busy timeout.

    ``statement_timeout_s`` ends any statement that runs longer (:mod:`db.timeouts`; on
    PostgreSQL, the statements of a transaction).
    A URL whose database or driver cannot be loaded is an :class:`InputError`.
    """
    try:
        check_database_url(url)
    except ValueError as exc:
        raise InputError(f"database URL: {exc}") from None
    parsed = make_url(url)
    sqlite = parsed.get_backend_name() == "sqlite"
    if sqlite and parsed.database and parsed.database != ":memory:":
        Path(parsed.database).expanduser().parent.mkdir(parents=True, exist_ok=True)
    engine = create_engine(parsed, **kwargs)
    if sqlite:
        _sqlite_events(engine, autocommit=kwargs.get("isolation_level") == "AUTOCOMMIT")
    if statement_timeout_s is not None:
        timeout = sqlite_statement_timeout if sqlite else postgres_statement_timeout
        timeout(engine, statement_timeout_s)
    return engine


class DatabaseUnavailableError(CalstationError):
    """The database does not answer (wrong URL, server down, no permission)."""

    @classmethod
    def of(cls, url: str | URL, exc: Exception) -> "DatabaseUnavailableError":
        """One line naming the database (password hidden) and the driver's first line."""
        shown = make_url(url).render_as_string(hide_password=True)
        driver = getattr(exc, "orig", None) or exc  # SQLAlchemy's errors wrap the driver's
        reason = (str(driver).strip().splitlines() or [type(driver).__name__])[0]
        return cls(f"database {shown} unavailable: {reason}")
