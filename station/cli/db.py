"""``calstation db upgrade``, ``calstation db rebuild-report``, ``calstation db
partitions``, ``calstation db backup|restore FILE``, ``calstation keys
create|revoke --station ID|--lab ID|--quality ID`` and ``calstation review SERIAL``: the
results database by hand."""

# Light to import: --help and refused arguments read only the signatures below;
# each command imports its work (numpy, SQLAlchemy, the loop, ...) when it runs.

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from pydantic import TypeAdapter, ValidationError

from station.cli.output import err, out
from station.domain.constants import Identifier, ReviewDecision
from station.domain.errors import InputError, validation_problem

if TYPE_CHECKING:
    from db.store import KeyScope

db_app = typer.Typer(
    help="The results database: schema migrations, the report's roll-ups, backups.",
    no_args_is_help=True,
)
keys_app = typer.Typer(
    help="API keys of the stations (runs), labs (gyro fits) and quality engineers (reviews "
    "of units on hold) that submit over HTTP.",
    no_args_is_help=True,
)

DatabaseUrlOption = Annotated[
    str | None,
    typer.Option(
        "--database-url",
        help="SQLAlchemy URL (default: CALSTATION_DATABASE_URL, else the embedded SQLite file).",
        show_default=False,
    ),
]


def _shown(url: str) -> str:
    from sqlalchemy import make_url

    return make_url(url).render_as_string(hide_password=True)


@db_app.command("rebuild-report")
def db_rebuild_report(
    limits: Annotated[
        Path | None,
        typer.Option("--limits", help="Limits profiles file (default: the shipped profiles)."),
    ] = None,
    profile: Annotated[
        str | None, typer.Option("--profile", help="Profile to bin the parameters against.")
    ] = None,
    database_url: DatabaseUrlOption = None,
) -> None:
    """Rebuild the end-of-line report's facts and roll-ups from the stored runs.

    The parameter roll-ups are binned against the profile's limits (default: the
    shipped default profile): run it when reports measure against other limits.
    """
    from sqlalchemy import func, select

    from db import DatabaseSettings, open_database
    from db.models import Run
    from db.rollups import lock_submissions, rebuild
    from station.domain.product.limits import load_profile
    from station.domain.quality.parameters import profile_bounds

    chosen = load_profile(limits, profile)
    url = database_url or DatabaseSettings.from_environment().url()
    database = open_database(url)
    try:
        with database.engine.begin() as connection:
            lock_submissions(connection)
            rebuild(connection, profile_bounds(chosen))
            runs = connection.scalar(select(func.count()).select_from(Run))
    finally:
        database.dispose()
    out.print(
        f"report roll-ups of {_shown(url)} rebuilt from {runs} runs, "
        f"parameters binned against {chosen.name} v{chosen.version}"
    )


@db_app.command("upgrade")
def db_upgrade(database_url: DatabaseUrlOption = None) -> None:
    """Migrate the database to the current schema (creating it if it is empty)."""
    from db import DatabaseSettings, upgrade_database

    url = database_url or DatabaseSettings.from_environment().url()
    upgrade = upgrade_database(url)
    if upgrade.before == upgrade.after:
        said = f"already at schema revision {upgrade.after}: nothing to migrate"
    elif upgrade.before is None:
        said = f"created at schema revision {upgrade.after}"
    else:
        said = f"migrated from schema revision {upgrade.before} to {upgrade.after}"
    out.print(f"database {_shown(url)} {said}", markup=False)


@db_app.command("partitions")
def db_partitions(
    ahead: Annotated[
        int, typer.Option("--ahead", help="Years to have past the current one.", min=0)
    ] = 1,
    database_url: DatabaseUrlOption = None,
) -> None:
    """Create the yearly partitions of runs and poses ahead (PostgreSQL; a daily or monthly
    job). Runs stored in the default partition (their year had none) move into their year."""
    from db import DatabaseSettings, open_database
    from db.partitions import add_years, require_partitioned

    url = database_url or DatabaseSettings.from_environment().url()
    require_partitioned(url)
    database = open_database(url)
    try:
        with database.engine.begin() as connection:
            years = add_years(connection, ahead)
    finally:
        database.dispose()
    created = ", ".join(map(str, years.created)) or "none"
    out.print(
        f"database {_shown(url)}: runs and poses by year from {years.first} to {years.last}; "
        f"created {created}; {years.moved} runs moved in from the default partition",
        markup=False,
    )


BackupFile = Annotated[
    Path,
    typer.Argument(
        metavar="FILE",
        help="The backup: a pg_dump archive (PostgreSQL) or a SQLite database file.",
    ),
]


@db_app.command("backup")
def db_backup(file: BackupFile, database_url: DatabaseUrlOption = None) -> None:
    """Back up the database to FILE while it serves: pg_dump's custom format on
    PostgreSQL, SQLite's online backup on SQLite. FILE must not exist yet."""
    from db import DatabaseSettings
    from db.backup import backup_database

    url = database_url or DatabaseSettings.from_environment().url()
    backup_database(url, file)
    out.print(f"database {_shown(url)} backed up to {file} ({file.stat().st_size} bytes)")


@db_app.command("restore")
def db_restore(
    file: BackupFile,
    replace: Annotated[
        bool,
        typer.Option("--replace", help="Replace what the database holds (default: refuse)."),
    ] = False,
    database_url: DatabaseUrlOption = None,
) -> None:
    """Restore the backup FILE into an empty database (``calstation db backup``); then
    ``calstation db upgrade`` brings a backup of an older schema up to date."""
    from db import DatabaseSettings
    from db.backup import restore_database

    url = database_url or DatabaseSettings.from_environment().url()
    restore_database(url, file, replace=replace)
    out.print(f"database {_shown(url)} restored from {file}")


def _name(value: str) -> str:
    """A station's, lab's, quality engineer's or reviewer's name, refused in words."""
    try:
        return TypeAdapter(Identifier).validate_python(value)
    except ValidationError as exc:
        raise typer.BadParameter(validation_problem(exc)) from None


def _optional_id(value: str | None) -> str | None:
    return None if value is None else _name(value)


StationOption = Annotated[
    str | None,
    typer.Option(
        "--station", help="A station's key: stores that station's runs.", callback=_optional_id
    ),
]
LabOption = Annotated[
    str | None,
    typer.Option("--lab", help="A lab's key: stores units' gyro fits.", callback=_optional_id),
]


QualityOption = Annotated[
    str | None,
    typer.Option(
        "--quality",
        help="A quality engineer's key: reviews units on hold.",
        callback=_optional_id,
    ),
]


def _holder(station: str | None, lab: str | None, quality: str | None) -> tuple[str, KeyScope]:
    """The key's holder and scope from ``--station``, ``--lab`` or ``--quality`` (one)."""
    scopes: tuple[tuple[str | None, KeyScope], ...] = (
        (station, "station"),
        (lab, "lab"),
        (quality, "quality"),
    )
    named = [(holder, scope) for holder, scope in scopes if holder is not None]
    if len(named) != 1:
        raise typer.BadParameter(
            "name one holder",
            param_hint="--station/--lab/--quality",
        )
    return named[0]


@keys_app.command("create")
def keys_create(
    station: StationOption = None,
    lab: LabOption = None,
    quality: QualityOption = None,
    database_url: DatabaseUrlOption = None,
) -> None:
    """Create an API key for a station (its runs), a lab (gyro fits) or a quality
    engineer (reviews of units on hold) and print it.

    Only the key's hash is stored: it is shown this once.
    """
    from db import repository_transaction

    holder, scope = _holder(station, lab, quality)
    with repository_transaction(database_url) as repository:
        key = repository.create_key(holder, scope)
    err.print(f"API key for {scope} {holder} (shown once, store it where it is used):")
    out.print(key)


@keys_app.command("revoke")
def keys_revoke(
    station: StationOption = None,
    lab: LabOption = None,
    quality: QualityOption = None,
    database_url: DatabaseUrlOption = None,
) -> None:
    """Revoke every API key of a station, a lab or a quality engineer (lost, replaced or
    retired)."""
    from db import repository_transaction

    holder, scope = _holder(station, lab, quality)
    with repository_transaction(database_url) as repository:
        revoked = repository.revoke_keys(holder, scope)
    out.print(
        f"revoked {revoked} API key of {scope} {holder}"
        if revoked == 1
        else f"revoked {revoked} API keys of {scope} {holder}"
    )


def review_command(
    serial: Annotated[str, typer.Argument(metavar="SERIAL", help="The unit on hold.")],
    decision: Annotated[
        ReviewDecision,
        typer.Option(help="retest: calibrate it again (attempts count afresh); scrap."),
    ],
    root_cause: Annotated[str, typer.Option("--root-cause", help="Why its latest run failed.")],
    repair: Annotated[str, typer.Option("--repair", help="What was repaired (or why not).")],
    by: Annotated[
        str, typer.Option("--by", help="Who reviewed it (a name, no spaces).", callback=_name)
    ],
    database_url: DatabaseUrlOption = None,
) -> None:
    """Review a unit on hold: release it for a retest, or scrap it (recorded, append-only).

    A unit sent to rework is refused at every station's scan until it is reviewed.
    """
    from db import ReviewRefusedError, repository_transaction
    from station.domain.record.records import HoldReview

    with repository_transaction(database_url) as repository:
        latest = repository.latest_for_serial(serial)
        if latest is None:
            raise InputError(f"no calibration run of serial {serial!r}")
        try:
            review = HoldReview(
                serial=serial,
                run_id=latest.run_id,
                reviewed_at=datetime.now(UTC),
                reviewer=by,
                root_cause=root_cause,
                repair_action=repair,
                decision=decision,
            )
        except ValidationError as exc:
            raise InputError(f"review: {validation_problem(exc)}") from None
        try:
            repository.add_review(review)
        except ReviewRefusedError as exc:
            raise InputError(str(exc)) from None
    out.print(f"{serial}: {decision} (run {latest.run_id}), reviewed by {by}")
