"""The results database: every calibration run, per serial number, for the whole plant.

Public surface::

    open_database(url=None) -> Database     embedded SQLite by default, migrated on first use
    RunRepository(session)                  submit and query runs, manage station keys
    DatabaseSettings                        CALSTATION_DATABASE_URL / CALSTATION_DATA_DIR

Errors (SQLAlchemy's own pass through, but for a lost connection at opening)::

    station.domain.errors.CalstationError
    ├── DatabaseUnavailableError    engine.py            the database does not answer
    ├── SchemaOutOfDateError        migrate.py           the schema is not the one this
    │                                                    software needs (behind, or newer)
    ├── RunConflictError            store/repository.py  a run with this UUID is stored
    │                                                    differently
    └── ReviewRefusedError          store/repository.py  a review of a unit not on hold

Layout: :mod:`db.store` writes and reads runs and units (submissions, a unit's page,
certificates, signatures, reviews, keys, run events); :mod:`db.report` holds the report's
queries, which read the store; the root keeps what both use (the tables of
:mod:`db.models`, the roll-ups of :mod:`db.rollups`, the engine, settings, migrations,
backups). ``db.store`` never imports ``db.report`` (an import-linter contract).
"""

from db.database import Database, open_database, repository_transaction, upgrade_database
from db.engine import DatabaseUnavailableError, make_async_engine, make_engine
from db.migrate import SchemaOutOfDateError
from db.settings import DatabaseSettings
from db.store import (
    ReviewRefusedError,
    RunConflictError,
    RunQuery,
    RunRepository,
    SubmitOutcome,
)

__all__ = [
    "Database",
    "DatabaseSettings",
    "DatabaseUnavailableError",
    "ReviewRefusedError",
    "RunConflictError",
    "RunQuery",
    "RunRepository",
    "SchemaOutOfDateError",
    "SubmitOutcome",
    "make_async_engine",
    "make_engine",
    "open_database",
    "repository_transaction",
    "upgrade_database",
]
