"""Where the results database lives.

``CALSTATION_DATABASE_URL`` names any SQLAlchemy URL (PostgreSQL for many stations,
``postgresql+psycopg://user@host/db``). Without it the station uses an embedded SQLite
file, ``calstation.sqlite3`` under ``CALSTATION_DATA_DIR`` (default
``$XDG_DATA_HOME/calstation``, i.e. ``~/.local/share/calstation``).
"""

import os
from pathlib import Path

from pydantic_settings import BaseSettings, SettingsConfigDict

SQLITE_FILE_NAME = "calstation.sqlite3"


def default_data_dir() -> Path:
    """``$XDG_DATA_HOME/calstation``, falling back to ``~/.local/share/calstation``."""
    base = os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share"
    return Path(base) / "calstation"


class DatabaseSettings(BaseSettings):
    """The database location, read from ``CALSTATION_*`` environment variables."""

    model_config = SettingsConfigDict(env_prefix="CALSTATION_", extra="ignore")

    database_url: str | None = None
    data_dir: Path = default_data_dir()

    def url(self) -> str:
        """The URL to connect to: the configured one or the embedded SQLite file."""
        if self.database_url:
            return self.database_url
        return f"sqlite:///{self.data_dir.expanduser() / SQLITE_FILE_NAME}"
