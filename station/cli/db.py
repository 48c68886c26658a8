"""``calstation db upgrade`` and ``calstation keys create``: the results database by hand."""

from typing import Annotated

import typer
from pydantic import TypeAdapter, ValidationError
from sqlalchemy import make_url

from db import DatabaseSettings, repository_transaction, upgrade_database
from station.cli.output import err, out
from station.records import Identifier

db_app = typer.Typer(help="The results database: schema migrations.", no_args_is_help=True)
keys_app = typer.Typer(help="API keys of the stations that submit over HTTP.", no_args_is_help=True)

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


@db_app.command("upgrade")
def db_upgrade(database_url: DatabaseUrlOption = None) -> None:
    """Migrate the database to the current schema (creating it if it is empty)."""
    url = database_url or DatabaseSettings().url()
    revision = upgrade_database(url)
    out.print(f"database {_shown(url)} at schema revision {revision}")


def _station_id(value: str) -> str:
    try:
        return TypeAdapter(Identifier).validate_python(value)
    except ValidationError:
        raise typer.BadParameter(
            "letters, digits and . _ : @ - only, at most 64 characters"
        ) from None


@keys_app.command("create")
def keys_create(
    station: Annotated[
        str, typer.Option("--station", help="The station the key is for.", callback=_station_id)
    ],
    database_url: DatabaseUrlOption = None,
) -> None:
    """Create an API key for a station and print it (only its hash is stored)."""
    with repository_transaction(database_url) as repository:
        key = repository.create_key(station)
    err.print(f"API key for station {station} (shown once, store it on the station):")
    out.print(key)


@keys_app.command("revoke")
def keys_revoke(
    station: Annotated[
        str,
        typer.Option(
            "--station", help="The station whose keys stop working.", callback=_station_id
        ),
    ],
    database_url: DatabaseUrlOption = None,
) -> None:
    """Revoke every API key of a station (a lost or replaced station)."""
    with repository_transaction(database_url) as repository:
        revoked = repository.revoke_keys(station)
    out.print(f"revoked {revoked} API key(s) of station {station}")
