"""Statement timeouts of the read connections: a slow read ends, it does not hold on.

PostgreSQL bounds every statement of a connection with ``statement_timeout``, given at
connection start in the URL's ``options`` (no round trip). SQLite has no such setting:
a progress handler, called every :data:`SQLITE_CHECK_EVERY` virtual-machine steps,
interrupts a statement that has run longer than the timeout (synchronous engines only,
where the handler can be installed on the connection itself). Either way the driver
raises an error that :func:`is_statement_timeout` recognises.
"""

import time
from typing import Any

from sqlalchemy import URL, Engine, event
from sqlalchemy.exc import DBAPIError

#: Virtual-machine steps of SQLite between two looks at the clock.
SQLITE_CHECK_EVERY = 10_000

#: PostgreSQL's SQLSTATE of a statement cancelled by ``statement_timeout``.
QUERY_CANCELED = "57014"


def with_statement_timeout(url: URL, seconds: float) -> URL:
    """``url`` whose PostgreSQL connections end statements after ``seconds``.

    Appended to the ``options`` the URL may already give (e.g. a ``search_path``).
    """
    given = url.query.get("options", "")
    options = " ".join(given) if isinstance(given, tuple) else given
    milliseconds = max(1, round(seconds * 1000))
    return url.update_query_dict(
        {"options": f"{options} -cstatement_timeout={milliseconds}".strip()}
    )


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
    if getattr(driver, "sqlstate", None) == QUERY_CANCELED:
        return True
    return type(driver).__module__ == "sqlite3" and str(driver) == "interrupted"
