"""Where the results database lives.

``CALSTATION_DATABASE_URL`` names any SQLAlchemy URL (PostgreSQL for many stations,
``postgresql+psycopg://user@host/db``). Without it the station uses an embedded SQLite
file, ``calstation.sqlite3`` under ``CALSTATION_DATA_DIR`` (default
``$XDG_DATA_HOME/calstation``, i.e. ``~/.local/share/calstation``).
``CALSTATION_DATABASE_PASSWORD`` gives the password apart from the URL: any characters
(``p@ss:w/rd``), no escaping by hand.
"""

import os
from pathlib import Path

from pydantic import SecretStr
from pydantic_settings import BaseSettings, SettingsConfigDict
from sqlalchemy import make_url

SQLITE_FILE_NAME = "calstation.sqlite3"


def default_data_dir() -> Path:
    """``$XDG_DATA_HOME/calstation``, falling back to ``~/.local/share/calstation``."""
    base = os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share"
    return Path(base) / "calstation"


class DatabaseSettings(BaseSettings):
    """The database location, read from ``CALSTATION_*`` environment variables."""

    model_config = SettingsConfigDict(env_prefix="CALSTATION_", extra="ignore")

    database_url: str | None = None
    database_password: SecretStr | None = None
    data_dir: Path = default_data_dir()

    def url(self) -> str:
        """The URL to connect to: the configured one or the embedded SQLite file.

        ``database_password`` replaces the URL's password, escaped as a URL needs it.
        """
        if self.database_url:
            if self.database_password is None:
                return self.database_url
            url = make_url(self.database_url).set(
                password=self.database_password.get_secret_value()
            )
            return url.render_as_string(hide_password=False)
        return f"sqlite:///{self.data_dir.expanduser() / SQLITE_FILE_NAME}"
