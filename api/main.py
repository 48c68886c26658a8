"""The results server's application factory (``uvicorn --factory api.main:create_app``)."""

from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from fastapi import APIRouter, FastAPI

from api.errors import install_error_handlers
from api.limits import BodySizeLimit
from api.routes import health, runs, units
from api.settings import ApiSettings
from db import open_database
from station import __version__

API_PREFIX = "/api/v1"


def create_app(settings: ApiSettings | None = None) -> FastAPI:
    """The API over the database ``settings`` name (default: from the environment).

    The database is opened at start-up: the embedded SQLite file is created and migrated
    if needed; a server database must already be at the current schema.
    """
    settings = settings or ApiSettings()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        app.state.database = open_database(settings.url())
        try:
            yield
        finally:
            app.state.database.dispose()

    app = FastAPI(
        title="calstation results",
        summary="Calibration runs of the smart putter, per serial number.",
        version=__version__,
        lifespan=lifespan,
    )
    app.state.settings = settings
    app.add_middleware(BodySizeLimit, max_bytes=settings.max_body_bytes)
    install_error_handlers(app)
    v1 = APIRouter(prefix=API_PREFIX)
    v1.include_router(units.router)
    v1.include_router(runs.router)
    app.include_router(health.router)
    app.include_router(v1)
    return app
