"""Backups of the results database, and restoring one into an empty database.

PostgreSQL is backed up by its own tools: ``pg_dump --format=custom`` writes one
archive of the whole database (schema, runs, units, reviews, keys, the report's
roll-ups and the schema revision), consistent as of one snapshot while the stations go
on submitting; ``pg_restore`` loads it into another database, owned by whoever
restores it (``--no-owner``), in one transaction. SQLite is copied page by page
through its online backup API (``sqlite3.Connection.backup``), also consistent while
the server writes, to a file that is itself a SQLite database.

A backup never overwrites a file, and is written beside it under another name first,
so that a half-written one is never taken for a backup. A restore goes into an empty
database (no table yet) unless told to replace what is there. The password travels to
the PostgreSQL tools in ``PGPASSWORD``, never on their command line.
"""

import os
import shutil
import sqlite3
import subprocess
from contextlib import closing
from pathlib import Path

from sqlalchemy import URL, inspect, make_url
from sqlalchemy.exc import OperationalError

from db.engine import DatabaseUnavailableError, make_engine
from station.domain.errors import InputError


def _libpq(url: str | URL) -> tuple[str, dict[str, str]]:
    """The libpq connection string of a PostgreSQL URL, and the environment that carries
    its password."""
    parsed = make_url(url)
    env = dict(os.environ)
    if parsed.password is not None:
        env["PGPASSWORD"] = str(parsed.password)
    dsn = parsed.set(drivername="postgresql", password=None).render_as_string()
    return dsn, env


def _run_tool(tool: str, *args: str, env: dict[str, str]) -> None:
    """Run a PostgreSQL client tool; its failure is an :class:`InputError` with its first
    line."""
    program = shutil.which(tool)
    if program is None:
        raise InputError(f"{tool} is not installed (PostgreSQL's client tools)")
    done = subprocess.run([program, *args], env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        lines = [line for line in done.stderr.splitlines() if line.strip()]
        raise InputError(f"{tool} failed: {lines[0] if lines else f'exit {done.returncode}'}")


def _sqlite_path(url: str | URL) -> Path:
    database = make_url(url).database
    if not database or database == ":memory:":
        raise InputError("an in-memory SQLite database has nothing to back up or restore")
    return Path(database).expanduser()


def _is_sqlite(url: str | URL) -> bool:
    return make_url(url).get_backend_name() == "sqlite"


def backup_database(url: str | URL, file: Path) -> None:
    """Write a backup of the database at ``url`` to ``file`` (a file that is not there).

    PostgreSQL: a ``pg_dump`` archive (custom format). SQLite: a copy of the database by
    its online backup API.
    """
    if file.exists():
        raise InputError(f"{file} exists: a backup never overwrites a file")
    if not file.parent.is_dir():
        raise InputError(f"{file.parent} is not a directory")
    partial = file.with_name(f".{file.name}.partial")
    try:
        if _is_sqlite(url):
            source = _sqlite_path(url)
            if not source.is_file():
                raise InputError(f"no SQLite database at {source}")
            with (
                closing(sqlite3.connect(source)) as origin,
                closing(sqlite3.connect(partial)) as copy,
            ):
                origin.backup(copy)
        else:
            dsn, env = _libpq(url)
            _run_tool("pg_dump", "--format=custom", f"--file={partial}", f"--dbname={dsn}", env=env)
        partial.rename(file)
    finally:
        partial.unlink(missing_ok=True)


def database_tables(url: str | URL) -> list[str]:
    """The tables of the database at ``url`` (of its default schema)."""
    engine = make_engine(url)
    try:
        with engine.connect() as connection:
            return inspect(connection).get_table_names()
    except OperationalError as exc:
        raise DatabaseUnavailableError.of(url, exc) from None
    finally:
        engine.dispose()


def restore_database(url: str | URL, file: Path, *, replace: bool = False) -> None:
    """Restore the backup ``file`` into the database at ``url``.

    The database must hold no table unless ``replace``: then what it holds is replaced
    by the backup's. Restored at the backup's schema revision: ``calstation db upgrade``
    brings an older one up to date.
    """
    if not file.is_file():
        raise InputError(f"no backup at {file}")
    if not _is_sqlite(url):
        _refuse_unless_empty(url, replace=replace)
        dsn, env = _libpq(url)
        options = ["--clean", "--if-exists"] if replace else []
        _run_tool(
            "pg_restore",
            "--no-owner",
            "--no-privileges",
            "--single-transaction",
            "--exit-on-error",
            *options,
            f"--dbname={dsn}",
            str(file),
            env=env,
        )
        return
    with closing(sqlite3.connect(f"{file.resolve().as_uri()}?mode=ro", uri=True)) as backup:
        try:
            backup.execute("PRAGMA schema_version").fetchone()
        except sqlite3.DatabaseError as exc:
            raise InputError(f"{file} is no SQLite backup: {exc}") from None
        _refuse_unless_empty(url, replace=replace)
        with closing(sqlite3.connect(_sqlite_path(url))) as database:
            backup.backup(database)


def _refuse_unless_empty(url: str | URL, *, replace: bool) -> None:
    tables = database_tables(url)
    if tables and not replace:
        raise InputError(
            f"the database holds {len(tables)} tables: restore into an empty database, "
            "or replace what it holds with --replace"
        )
