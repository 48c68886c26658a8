"""``GET /api/v1/events``: the line's stored runs as server-sent events, as they are stored.

The line dashboard (``GET /``) listens to it and brings its rows up to date without a
reload. The stream is ``text/event-stream`` (the WHATWG server-sent events format, as
FastAPI writes it: :class:`fastapi.sse.EventSourceResponse`): one event per stored run,
its ``data`` a :class:`api.schemas.RunEvent`, and a ``: ping`` comment every 15 s of quiet
so that proxies keep the connection open.

Each server process answers its own listeners by asking the database, every
:data:`POLL_S`, for the runs stored after the last one it sent (:mod:`db.run_events`):
one primary-key range read per listener and poll, on a reader connection taken for that
read only, whichever server process stored the run. A stream holds every run stored after
its headers were sent; a listener that lost its connection reloads what it shows (the
dashboard does).
"""

import asyncio
import logging
from collections.abc import AsyncIterator
from typing import Annotated

from fastapi import APIRouter, Depends
from fastapi.sse import EventSourceResponse
from sqlalchemy.exc import DBAPIError

from api.deps import ReadersDep
from api.responses import json_problems
from api.schemas import RunEvent
from db.run_events import last_stored, stored_after

log = logging.getLogger(__name__)

#: Seconds between a listener's reads of the runs stored since the last it was sent.
POLL_S = 1.0
#: Most runs read at once.
BATCH = 100

router = APIRouter(tags=["events"])


async def _last_stored(readers: ReadersDep) -> int:
    """The latest stored run's id, read before the answer starts: a client that has the
    answer's headers gets every run stored after that."""
    async with readers() as session:
        return await session.run_sync(last_stored)


@router.get(
    "/events",
    response_class=EventSourceResponse,
    response_description="`text/event-stream`: one event per stored run, its `data` a "
    "`RunEvent` (JSON), from the next run stored on; a `: ping` comment every 15 s of "
    "quiet. The stream does not end.",
    responses=json_problems(413, 422, 503),
)
async def get_events(
    readers: ReadersDep, after: Annotated[int, Depends(_last_stored)]
) -> AsyncIterator[RunEvent]:
    """The line's runs as they are stored, as server-sent events (the dashboard follows it).

    Each event arrives within about a second of the run's storing; the stream holds every
    run stored after its answer's headers were sent.
    """
    try:
        while True:
            async with readers() as session:
                rows = await session.run_sync(stored_after, after, BATCH)
            for row in rows:
                after = row.id
                yield RunEvent(
                    run_id=row.run_id,
                    serial=row.serial,
                    station_id=row.station_id,
                    operator_id=row.operator_id,
                    lot=row.lot,
                    started_at=row.started_at,
                    finished_at=row.finished_at,
                    verdict=row.verdict,
                    disposition=row.disposition,
                    failure=row.failure,
                    unit=f"/units/{row.serial}",
                )
            if len(rows) < BATCH:
                await asyncio.sleep(POLL_S)
    except DBAPIError as exc:  # the stream ends; a browser reconnects by itself
        log.warning("event stream ended: %s", (str(exc).splitlines() or [repr(exc)])[0])
