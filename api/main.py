"""The results server's application factory (``uvicorn --factory api.main:create_app``)."""

import asyncio
import contextlib
import gc
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

from fastapi import APIRouter, Depends, FastAPI
from fastapi_offline import FastAPIOffline
from sqlalchemy.ext.asyncio import async_sessionmaker
from sqlalchemy.orm import configure_mappers

from api.alerts import AlertLoop
from api.deps import require_key
from api.errors import install_error_handlers
from api.limits import BodySizeLimit
from api.metrics import install_metrics
from api.redoc import add_redoc
from api.report_pool import ReportPool
from api.responses import json_problems, problems
from api.routes import (
    alerts,
    certificates,
    events,
    gyro,
    health,
    reports,
    reviews,
    runs,
    unit_pages,
    units,
)
from api.settings import ApiSettings
from db import make_async_engine, open_database
from db.store import UnitLookups
from station import __version__
from station.domain.quality.shifts import parse_shifts

API_PREFIX = "/api/v1"


def create_app(settings: ApiSettings | None = None) -> FastAPI:
    """The API over the database ``settings`` name (default: from the environment).

    The database is opened at start-up: the embedded SQLite file is created and migrated
    if needed; a server database must already be at the current schema.
    """
    settings = settings or ApiSettings()
    rules = settings.alert_rules()

    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        url = settings.url()
        open_database(url).dispose()  # creates/migrates SQLite, checks a server's schema
        # Fixed pools, no overflow: under load an overflow connection is opened for one
        # request and closed after it, a new server process each time on PostgreSQL.
        # Requests beyond the pool wait for a connection instead.
        options = settings.engine_options()
        writer = make_async_engine(
            url, pool_size=settings.write_pool_size, max_overflow=0, **options
        )
        # A read is a transaction: its statement timeout is set in it (SET LOCAL,
        # db/timeouts.py), the one way the timeout holds through a pooler in transaction
        # mode. Three round trips more than autocommit (BEGIN, SET LOCAL, ROLLBACK); the
        # unit lookups keep an autocommit connection of their own (db/store/units.py).
        reader = make_async_engine(
            url,
            statement_timeout_s=settings.read_timeout_s,
            pool_size=settings.read_pool_size,
            max_overflow=0,
            **options,
        )
        # The report and the dashboard: processes and connections of their own, on the
        # streaming replica when one is configured.
        app.state.report_pool = report_pool = ReportPool(
            settings.report_url(),
            processes=settings.report_pool_size,
            wait_s=settings.report_wait_s,
            timeout_s=settings.read_timeout_s,
            metrics=server_metrics,
            engine_options=options,
        )
        app.state.sessions = async_sessionmaker(writer, expire_on_commit=False)
        app.state.readers = async_sessionmaker(reader, expire_on_commit=False)
        lookups = app.state.unit_lookups = UnitLookups(reader)  # keeps one reader connection
        # The models' mappers are configured on first use (about 10 ms): done here, the
        # first request that needs them does not hold up the requests beside it.
        configure_mappers()
        # What start-up allocated (modules, routes, models) lives as long as the process:
        # keep it out of the collector's full passes, which otherwise walk it all and
        # stall requests for milliseconds at a time. Kept for the lookups' p99 target
        # (docs/benchmarks.md): without it, 216,000 objects more in each full pass; one
        # server process at 1,000 lookups/s beside 10 submissions/s paused 2.85 s in 15 s
        # (full passes up to 560 ms) against 1.36 s (up to 85 ms) with it, and answered
        # 574-578 lookups/s against 683-690/s (back to back twice, on a loaded machine).
        # Frozen without a collection first: one full pass costs ~0.2 s of the start, and
        # the garbage it would free (some 1,300 objects of the imports: functions, tuples,
        # classes made on the way) holds no resource; kept, it weighs a few hundred KB. A
        # first start that migrates the embedded database keeps the migrations' leftovers
        # too, for that process's life (their engine is disposed: memory, not files).
        gc.freeze()
        # On from here (calstation serve holds the collector off while the server loads).
        gc.enable()
        alerting = None
        if rules is not None:
            loop = AlertLoop(
                app.state.sessions, rules, settings.alert_interval_s, settings.alert_retry_s
            )
            app.state.alert_loop = loop
            alerting = asyncio.create_task(loop.run())
        try:
            yield
        finally:
            if alerting is not None:
                alerting.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await alerting
            await lookups.close()
            await writer.dispose()
            await reader.dispose()
            report_pool.close()

    # /docs and /redoc from the Swagger UI and ReDoc files the fastapi-offline package
    # ships (under /static-offline-docs), not from a CDN: they work in a plant offline.
    app: FastAPI = FastAPIOffline(
        redoc_url=None,  # api.redoc serves it, without the bundle's one CDN address
        title="calstation results",
        summary="Calibration runs of the smart putter, per serial number.",
        version=__version__,
        lifespan=lifespan,
        responses=problems(413, 503),
    )
    add_redoc(app)
    app.state.event_listeners = events.Listeners(settings.event_listeners)
    app.state.plant_timezone = settings.plant_timezone
    app.state.laboratory = settings.laboratory()
    app.state.plant_shifts = parse_shifts(settings.plant_shifts)
    app.state.export_page_size = settings.export_page_size
    app.state.alert_loop = None
    app.add_middleware(BodySizeLimit, max_bytes=settings.max_body_bytes)
    install_error_handlers(app)
    reads = [Depends(require_key)] if settings.read_requires_key else []
    keyed = problems(401) if settings.read_requires_key else None
    v1 = APIRouter(prefix=API_PREFIX, responses=problems(422))
    v1.include_router(units.router, dependencies=reads, responses=keyed)
    v1.include_router(runs.router, dependencies=reads, responses=keyed)
    v1.include_router(runs.submissions)
    v1.include_router(gyro.router, dependencies=reads, responses=keyed)
    v1.include_router(gyro.submissions)
    v1.include_router(reviews.router, dependencies=reads, responses=keyed)
    v1.include_router(reviews.submissions)
    v1.include_router(reports.router, dependencies=reads, responses=keyed)
    v1.include_router(certificates.router, dependencies=reads, responses=keyed)
    # The event stream's own answer is not JSON: its errors name their media type.
    keyed_stream = json_problems(401) if settings.read_requires_key else None
    v1.include_router(events.router, dependencies=reads, responses=keyed_stream)
    app.include_router(health.router)
    app.include_router(v1)
    app.include_router(reports.dashboard, dependencies=reads)
    app.include_router(unit_pages.router, dependencies=reads, responses=keyed)
    app.include_router(alerts.router, dependencies=reads, responses=keyed)
    # Last: its middleware is the outermost, so it sees every answer (a 413 too).
    server_metrics = install_metrics(app)
    return app
