"""``calstation serve``: the results server (REST API) under uvicorn."""

# Light to import: --help and refused arguments read only the signatures below;
# each command imports its work (numpy, SQLAlchemy, the loop, ...) when it runs.

import copy
import gc
import os
import tempfile
from typing import Annotated, Any

import typer

#: Seconds a stopping server gives the requests still open before it cancels them: the
#: line dashboard's event stream never ends by itself (``GET /api/v1/events``), and a
#: container is killed 10 s after it is asked to stop.
GRACEFUL_SHUTDOWN_S = 5


def _log_config() -> dict[str, Any]:
    """Uvicorn's logging, plus one line per submitted run from the ``api`` loggers."""
    import uvicorn.config

    config = copy.deepcopy(uvicorn.config.LOGGING_CONFIG)
    config["loggers"]["api"] = {"handlers": ["default"], "level": "INFO", "propagate": False}
    return config


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
    # No collector passes while the server loads: its imports and start-up allocate
    # objects that live as long as the process (some 200,000), and the collector's passes
    # over them cost ~0.25 s of a start and free next to nothing. The application's
    # start-up freezes them and turns the collector back on (api.main); a start that
    # fails, or a server that stops, turns it back on here.
    gc.disable()
    try:
        _serve(host, port, workers, database_url)
    finally:
        gc.enable()


def _serve(host: str, port: int, workers: int, database_url: str | None) -> None:
    """:func:`serve`'s work, the collector off."""
    import uvicorn

    from api.settings import ApiSettings
    from db import open_database

    if database_url:
        os.environ["CALSTATION_DATABASE_URL"] = database_url
    # Migrate the embedded database (or check a server's schema) once, before the
    # workers start, so they never race on it and a bad URL fails here in one line.
    open_database(ApiSettings.from_environment().url()).dispose()
    with tempfile.TemporaryDirectory(prefix="calstation-metrics-") as metrics_dir:
        # Several workers: each counts into files here, and whichever answers /metrics
        # adds them all up (prometheus-client's multiprocess mode, api/metrics.py).
        if workers > 1:
            os.environ.setdefault("PROMETHEUS_MULTIPROC_DIR", metrics_dir)
            gc.enable()  # this process only supervises the workers, each a fresh one
        uvicorn.run(
            "api.main:create_app",
            factory=True,
            host=host,
            port=port,
            workers=workers,
            log_config=_log_config(),
            log_level="info",
            access_log=False,
            timeout_graceful_shutdown=GRACEFUL_SHUTDOWN_S,
        )
