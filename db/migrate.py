"""Schema migrations (Alembic), run from the installed package: no ``alembic.ini`` needed.

Alembic is imported only to migrate (or to read the packaged scripts): a database
already at :data:`HEAD_REVISION`, as every server start finds it, is checked with one
plain query of Alembic's version table, so opening it costs no Alembic import (~0.2 s
of a start; docs/benchmarks.md, "Server start").
"""

from typing import TYPE_CHECKING

from sqlalchemy import Connection, Engine, text

from station.domain.errors import CalstationError

if TYPE_CHECKING:
    from alembic.config import Config

SCRIPT_LOCATION = "db:migrations"
#: The newest revision the packaged migrations reach: the schema this software needs.
#: A new migration moves it (tests/db/test_migrations.py holds it to Alembic's own
#: reading of the scripts).
HEAD_REVISION = "0025"
#: Alembic's version table: one row, the revision the schema is at (none when empty).
VERSION_TABLE = "alembic_version"


class SchemaOutOfDateError(CalstationError):
    """The database's schema is not the one this software expects."""


def alembic_config(connection: Connection | None = None) -> "Config":
    """An Alembic configuration for the packaged migrations, bound to ``connection``."""
    from alembic.config import Config

    config = Config()
    config.set_main_option("script_location", SCRIPT_LOCATION)
    config.attributes["connection"] = connection
    return config


def current_revision(engine: Engine) -> str | None:
    """The revision the database is at (``None`` for an empty database), read by Alembic."""
    from alembic.runtime.migration import MigrationContext

    with engine.connect() as connection:
        return MigrationContext.configure(connection).get_current_revision()


def migrate_schema(connection: Connection, revision: str = "head") -> None:
    """Migrate the schema on ``connection`` up to ``revision`` (within its transaction).

    :class:`SchemaOutOfDateError` for a revision the packaged migrations do not know.
    """
    from alembic import command
    from alembic.util.exc import CommandError

    try:
        command.upgrade(alembic_config(connection), revision)
    except CommandError as exc:  # a revision the packaged migrations do not know
        url = connection.engine.url.render_as_string(hide_password=True)
        raise SchemaOutOfDateError(
            f"database {url} cannot be migrated to {revision}: {exc} "
            "(written by a newer calstation?)"
        ) from None


def stored_revisions(connection: Connection) -> list[str]:
    """The revisions in the database's version table, sorted: none for an empty
    database, one for a migrated one (more only if its table was written by hand)."""
    if not connection.dialect.has_table(connection, VERSION_TABLE):
        return []
    return sorted(connection.scalars(text(f"SELECT version_num FROM {VERSION_TABLE}")))


def is_at_head(connection: Connection) -> bool:
    """Whether the schema on ``connection`` is exactly :data:`HEAD_REVISION`."""
    return stored_revisions(connection) == [HEAD_REVISION]


def require_current(engine: Engine) -> None:
    """Refuse a database whose schema is not at the packaged head."""
    with engine.connect() as connection:
        stored = stored_revisions(connection)
    if stored != [HEAD_REVISION]:
        url = engine.url.render_as_string(hide_password=True)
        raise SchemaOutOfDateError(
            f"database {url} is at schema revision {', '.join(stored) or 'none'}, this "
            f"software needs {HEAD_REVISION}: run 'calstation db upgrade'"
        )
