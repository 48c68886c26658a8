"""``calstation db upgrade``, ``calstation db rebuild-report`` and ``calstation keys
create|revoke --station ID|--lab ID``: the results database by hand."""

from pathlib import Path
from typing import Annotated, cast

import typer
from pydantic import TypeAdapter, ValidationError
from sqlalchemy import func, make_url, select

from db import DatabaseSettings, open_database, repository_transaction, upgrade_database
from db.models import Run
from db.repository import KeyScope
from db.rollups import lock_submissions, rebuild
from station.cli.output import err, out
from station.domain.limits import load_profile
from station.domain.quality.parameters import profile_bounds
from station.domain.records import Identifier

db_app = typer.Typer(
    help="The results database: schema migrations, the report's roll-ups.", no_args_is_help=True
)
keys_app = typer.Typer(
    help="API keys of the stations (runs) and labs (gyro fits) that submit over HTTP.",
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
    url = database_url or DatabaseSettings.from_environment().url()
    revision = upgrade_database(url)
    out.print(f"database {_shown(url)} at schema revision {revision}")


def _station_id(value: str) -> str:
    try:
        return TypeAdapter(Identifier).validate_python(value)
    except ValidationError:
        raise typer.BadParameter(
            "letters, digits and . _ : @ - only, at most 64 characters"
        ) from None


def _optional_id(value: str | None) -> str | None:
    return None if value is None else _station_id(value)


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


def _holder(station: str | None, lab: str | None) -> tuple[str, KeyScope]:
    """The key's holder and scope from ``--station`` or ``--lab`` (exactly one)."""
    if (station is None) == (lab is None):
        raise typer.BadParameter(
            "give either --station ID or --lab ID", param_hint="--station/--lab"
        )
    return (station, "station") if station is not None else (cast(str, lab), "lab")


@keys_app.command("create")
def keys_create(
    station: StationOption = None, lab: LabOption = None, database_url: DatabaseUrlOption = None
) -> None:
    """Create an API key for a station (its runs) or a lab (gyro fits) and print it.

    Only the key's hash is stored: it is shown this once.
    """
    holder, scope = _holder(station, lab)
    with repository_transaction(database_url) as repository:
        key = repository.create_key(holder, scope)
    err.print(f"API key for {scope} {holder} (shown once, store it where it is used):")
    out.print(key)


@keys_app.command("revoke")
def keys_revoke(
    station: StationOption = None, lab: LabOption = None, database_url: DatabaseUrlOption = None
) -> None:
    """Revoke every API key of a station or a lab (lost, replaced or retired)."""
    holder, scope = _holder(station, lab)
    with repository_transaction(database_url) as repository:
        revoked = repository.revoke_keys(holder, scope)
    out.print(f"revoked {revoked} API key(s) of {scope} {holder}")
