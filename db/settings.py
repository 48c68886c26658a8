"""Where the results database lives.

``CALSTATION_DATABASE_URL`` names any SQLAlchemy URL of a supported database
(PostgreSQL for many stations, ``postgresql+psycopg://user@host/db``). Without it the
station uses an embedded SQLite file, ``calstation.sqlite3`` under
``CALSTATION_DATA_DIR`` (default ``$XDG_DATA_HOME/calstation``, i.e.
``~/.local/share/calstation``). Both are checked when read: a URL whose scheme or
driver cannot be loaded, or a data directory that is a file, is refused at once rather
than when the first run is stored.
``CALSTATION_DATABASE_PASSWORD`` gives the password apart from the URL: any characters
(``p@ss:w/rd``), no escaping by hand.
"""

import os
from pathlib import Path
from typing import Annotated, Self

from pydantic import AfterValidator, SecretStr, ValidationError
from pydantic_settings import BaseSettings, SettingsConfigDict
from sqlalchemy import URL, make_url
from sqlalchemy.exc import ArgumentError, NoSuchModuleError

from station.domain.errors import InputError, validation_problem

SQLITE_FILE_NAME = "calstation.sqlite3"
#: The databases the results' schema and statements are written for.
SUPPORTED_BACKENDS = ("postgresql", "sqlite")


def default_data_dir() -> Path:
    """``$XDG_DATA_HOME/calstation``, falling back to ``~/.local/share/calstation``."""
    base = os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share"
    return Path(base) / "calstation"


def check_database_url(url: str | URL) -> str | URL:
    """``url`` if it names a supported database whose driver is installed.

    Raises ``ValueError`` naming the problem (an unknown scheme, an unsupported
    database, a driver not installed); the password never appears in it.
    """
    try:
        parsed = make_url(url)
    except ArgumentError:
        raise ValueError(
            "not a database URL (e.g. postgresql+psycopg://user@host/db or sqlite:///path)"
        ) from None
    try:
        dialect = parsed.get_dialect()
    except NoSuchModuleError:
        raise ValueError(
            f"unknown scheme {parsed.drivername!r} (use postgresql+psycopg:// or sqlite:///)"
        ) from None
    backend = parsed.get_backend_name()
    if backend not in SUPPORTED_BACKENDS:
        raise ValueError(f"database {backend!r} is not supported (use postgresql or sqlite)")
    try:
        dialect.import_dbapi()
    except ImportError:
        raise ValueError(
            f"the driver of {parsed.drivername!r} is not installed (use postgresql+psycopg://)"
        ) from None
    return url


def _a_directory(path: Path) -> Path:
    if path.expanduser().exists() and not path.expanduser().is_dir():
        raise ValueError(f"{path} is a file, not a directory")
    return path


#: A data directory: absent (made on first use) or a directory, never a file.
DataDir = Annotated[Path, AfterValidator(_a_directory)]
#: A database URL that :func:`check_database_url` accepts.
DatabaseUrl = Annotated[str, AfterValidator(check_database_url)]


class DatabaseSettings(BaseSettings):
    """The database location, read from ``CALSTATION_*`` environment variables."""

    model_config = SettingsConfigDict(env_prefix="CALSTATION_", extra="ignore")

    database_url: DatabaseUrl | None = None
    database_password: SecretStr | None = None
    data_dir: DataDir = default_data_dir()

    @classmethod
    def from_environment(cls) -> Self:
        """The settings of the environment; a bad value is an :class:`InputError`."""
        try:
            return cls()
        except ValidationError as exc:
            prefix = str(cls.model_config.get("env_prefix", ""))
            raise InputError(validation_problem(exc, env_prefix=prefix)) from None

    def url(self) -> str:
        """The URL to connect to: the configured one or the embedded SQLite file.

        ``database_password`` replaces the URL's password, escaped as a URL needs it.
        """
        if not self.database_url:
            return f"sqlite:///{self.data_dir.expanduser() / SQLITE_FILE_NAME}"
        if self.database_password is None:
            return self.database_url
        url = make_url(self.database_url).set(password=self.database_password.get_secret_value())
        return url.render_as_string(hide_password=False)
