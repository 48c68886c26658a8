"""The results database opened: migrated (or its schema checked), with its sessions.

Opening the embedded SQLite database migrates it to the packaged head; a server
database is migrated by ``calstation db upgrade`` and refused when behind.

Derived data: the unit answers (:mod:`db.store.units`) and the report's facts and
roll-ups (:mod:`db.rollups`) are functions of ``runs``. The migrations create their
tables only; when they are empty beside stored runs (a migration just added them, or
emptied facts of an older yield definition, as 0021 did), or the answers are of an older
shape, :func:`rewrite_if_stale` writes both from ``runs`` in the upgrade's transaction.
"""

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from sqlalchemy import Connection, Engine, select
from sqlalchemy.exc import OperationalError
from sqlalchemy.orm import Session, sessionmaker

from db.engine import DatabaseUnavailableError, make_engine
from db.migrate import current_revision, is_at_head, migrate_schema, require_current
from db.models import Run, RunFacts, Unit
from db.rollups import lock_submissions, rebuild, stored_bounds
from db.settings import DatabaseSettings
from db.store import RunRepository
from db.store.units import answers_are_stale, refresh_answers


def upgrade(engine: Engine, revision: str = "head") -> None:
    """Migrate the database up to ``revision`` in one transaction; at the head, derived
    data of an older definition is rewritten too. A database already at the head, as
    every opening but the first finds it, is left to the derived data's check: Alembic
    would find nothing to do, and is not imported for it."""
    with engine.begin() as connection:
        if not (revision == "head" and is_at_head(connection)):
            migrate_schema(connection, revision)
        if revision == "head":
            rewrite_if_stale(connection)


def rewrite_if_stale(connection: Connection) -> bool:
    """Write the answers and the report's roll-ups if they are missing or stale."""
    session = Session(bind=connection)
    if not (_missing(session) or answers_are_stale(session)):
        return False
    lock_submissions(connection)
    refresh_answers(session)
    session.flush()
    rebuild(connection, stored_bounds(connection) or None)
    return True


def _missing(session: Session) -> bool:
    """Whether runs are stored but the answers or the roll-ups were never written."""
    if session.scalars(select(Run.id).limit(1)).first() is None:
        return False
    no_units = session.scalars(select(Unit.serial).limit(1)).first() is None
    return no_units or session.scalars(select(RunFacts.run_pk).limit(1)).first() is None


class Database:
    """One results database: its engine and a factory of sessions."""

    def __init__(self, engine: Engine) -> None:
        self.engine = engine
        #: A new session on each call (use it as a context manager).
        self.session = sessionmaker(engine, expire_on_commit=False)

    @property
    def is_sqlite(self) -> bool:
        """Whether this is the embedded (SQLite) database."""
        return self.engine.dialect.name == "sqlite"

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
    engine = make_engine(url or DatabaseSettings.from_environment().url())
    database = Database(engine)
    try:
        if auto_migrate if auto_migrate is not None else database.is_sqlite:
            upgrade(engine)
        else:
            require_current(engine)
    except OperationalError as exc:
        database.dispose()
        raise DatabaseUnavailableError.of(engine.url, exc) from None
    except BaseException:
        database.dispose()
        raise
    return database


@dataclass(frozen=True)
class Upgrade:
    """What :func:`upgrade_database` found and left: the schema revision before (None: an
    empty database) and after."""

    before: str | None
    after: str


def upgrade_database(url: str | None = None) -> Upgrade:
    """Migrate the database at ``url`` to the packaged head."""
    engine = make_engine(url or DatabaseSettings.from_environment().url())
    try:
        before = current_revision(engine)
    except OperationalError as exc:
        raise DatabaseUnavailableError.of(engine.url, exc) from None
    finally:
        engine.dispose()
    database = open_database(url, auto_migrate=True)
    try:
        after = current_revision(database.engine)
    finally:
        database.dispose()
    assert after is not None
    return Upgrade(before, after)


@contextmanager
def repository_transaction(url: str | None = None) -> Iterator[RunRepository]:
    """A repository in one transaction on the database at ``url``, for one-off commands.

    Opens the database (as :func:`open_database`), commits when the block ends
    normally, and disposes of the connections either way.
    """
    database = open_database(url)
    try:
        with database.session() as session, session.begin():
            yield RunRepository(session)
    finally:
        database.dispose()
