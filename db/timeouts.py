"""Statement timeouts of the read connections: a slow read ends, it does not hold on.

PostgreSQL bounds every statement of a transaction with ``statement_timeout``, set by
``SET LOCAL`` as each transaction begins: it lasts as long as the transaction, so it
holds through a pooler in transaction mode (pgbouncer), which lends a PostgreSQL
connection for one transaction and refuses, or ignores, a connection's startup options
(``-c statement_timeout``); nor does it stay behind on the pooled connection for the next
client. Statements outside a transaction (autocommit) run without it. SQLite has no such setting:
a progress handler, called every :data:`SQLITE_CHECK_EVERY` virtual-machine steps,
interrupts a statement that has run longer than the timeout (synchronous engines only,
where the handler can be installed on the connection itself). Either way the driver
raises an error that :func:`is_statement_timeout` recognises.
"""

import time
from typing import Any

from sqlalchemy import Connection, Engine, event
from sqlalchemy.exc import DBAPIError

#: Virtual-machine steps of SQLite between two looks at the clock.
SQLITE_CHECK_EVERY = 10_000

#: PostgreSQL's SQLSTATE of a statement cancelled by ``statement_timeout``.
QUERY_CANCELED = "57014"


def postgres_statement_timeout(engine: Engine, seconds: float) -> None:
    """End the statements of ``engine``'s PostgreSQL transactions after ``seconds``.

    One ``SET LOCAL`` as each transaction begins (a round trip after ``BEGIN``); none on
    a connection in autocommit, which has no transaction to hold it. An asyncio engine is
    given by its ``sync_engine``.
    """
    milliseconds = max(1, round(seconds * 1000))

    @event.listens_for(engine, "begin")
    def _set(connection: Connection) -> None:
        if not connection.connection.dbapi_connection.autocommit:  # type: ignore[union-attr]
            connection.exec_driver_sql(f"SET LOCAL statement_timeout = {milliseconds}")


def sqlite_statement_timeout(engine: Engine, seconds: float) -> None:
    """Interrupt the statements of ``engine``'s SQLite connections after ``seconds``."""

    @event.listens_for(engine, "connect")
    def _install(dbapi_connection: Any, record: Any) -> None:
        deadline = record.info["deadline"] = [float("inf")]
        dbapi_connection.set_progress_handler(
            lambda: time.monotonic() > deadline[0], SQLITE_CHECK_EVERY
        )

    @event.listens_for(engine, "before_cursor_execute")
    def _start(connection: Any, *_args: Any) -> None:
        connection.info["deadline"][0] = time.monotonic() + seconds


def is_statement_timeout(exc: DBAPIError) -> bool:
    """Whether the database ended the statement for running too long."""
    driver = exc.orig
    postgres = getattr(driver, "sqlstate", None) == QUERY_CANCELED
    return postgres or (type(driver).__module__ == "sqlite3" and str(driver) == "interrupted")
