"""``calstation serve``: the results server (REST API) under uvicorn."""

import os
from typing import Annotated

import typer
import uvicorn
from sqlalchemy.exc import OperationalError

from api.settings import ApiSettings
from db import open_database
from station.errors import CalstationError


def serve(
    host: Annotated[str, typer.Option(help="Address to listen on.")] = "127.0.0.1",
    port: Annotated[int, typer.Option(min=1, max=65535, help="TCP port.")] = 8000,
    workers: Annotated[int, typer.Option(min=1, help="Worker processes.")] = 1,
    database_url: Annotated[
        str | None,
        typer.Option(
            "--database-url",
            help="SQLAlchemy URL (default: CALSTATION_DATABASE_URL, else the embedded SQLite).",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Serve the results API (OpenAPI at /docs)."""
    if database_url:
        os.environ["CALSTATION_DATABASE_URL"] = database_url
    url = ApiSettings().url()
    # Migrate the embedded database (or check a server's schema) once, before the
    # workers start, so they never race on it and a bad URL fails here in one line.
    try:
        open_database(url).dispose()
    except OperationalError as exc:
        raise CalstationError(f"results database unavailable: {exc.orig}") from None
    uvicorn.run(
        "api.main:create_app",
        factory=True,
        host=host,
        port=port,
        workers=workers,
        log_level="warning",
        access_log=False,
    )
