"""Schema migrations (Alembic), run from the installed package: no ``alembic.ini`` needed."""

from alembic import command
from alembic.config import Config
from alembic.runtime.migration import MigrationContext
from alembic.script import ScriptDirectory
from alembic.util.exc import CommandError
from sqlalchemy import Connection, Engine

from station.domain.errors import CalstationError

SCRIPT_LOCATION = "db:migrations"


class SchemaOutOfDateError(CalstationError):
    """The database's schema is not the one this software expects."""


def alembic_config(connection: Connection | None = None) -> Config:
    """An Alembic configuration for the packaged migrations, bound to ``connection``."""
    config = Config()
    config.set_main_option("script_location", SCRIPT_LOCATION)
    config.attributes["connection"] = connection
    return config


def head_revision() -> str:
    """The newest revision the packaged migrations reach."""
    head = ScriptDirectory.from_config(alembic_config()).get_current_head()
    assert head is not None, "the packaged migrations have no head"
    return head


def current_revision(engine: Engine) -> str | None:
    """The revision the database is at (``None`` for an empty database)."""
    with engine.connect() as connection:
        return MigrationContext.configure(connection).get_current_revision()


def migrate_schema(connection: Connection, revision: str = "head") -> None:
    """Migrate the schema on ``connection`` up to ``revision`` (within its transaction).

    :class:`SchemaOutOfDateError` for a revision the packaged migrations do not know.
    """
    try:
        command.upgrade(alembic_config(connection), revision)
    except CommandError as exc:  # a revision the packaged migrations do not know
        url = connection.engine.url.render_as_string(hide_password=True)
        raise SchemaOutOfDateError(
            f"database {url} cannot be migrated to {revision}: {exc} "
            "(written by a newer calstation?)"
        ) from None


def require_current(engine: Engine) -> None:
    """Refuse a database whose schema is not at the packaged head."""
    current, head = current_revision(engine), head_revision()
    if current != head:
        url = engine.url.render_as_string(hide_password=True)
        raise SchemaOutOfDateError(
            f"database {url} is at schema revision {current or 'none'}, this software needs "
            f"{head}: run 'calstation db upgrade'"
        )
