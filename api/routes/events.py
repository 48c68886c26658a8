"""``GET /api/v1/events``: the line's stored runs as server-sent events, as they are stored.

The line dashboard (``GET /``) listens to it and brings its rows up to date without a
reload. The stream is ``text/event-stream`` (the WHATWG server-sent events format, as
FastAPI writes it: :class:`fastapi.sse.EventSourceResponse`): one event per stored run,
its ``data`` a :class:`api.schemas.RunEvent`, and a ``: ping`` comment every 15 s of quiet
so that proxies keep the connection open.

Each server process answers its own listeners by asking the database, every
:data:`POLL_S`, for the runs stored after the last one it sent (:mod:`db.store.run_events`):
one primary-key range read per listener and poll, on a reader connection taken for that
read only, whichever server process stored the run. A stream holds every run stored after
its headers were sent; a listener that lost its connection reloads what it shows (the
dashboard does).

What a listener costs, and its budget: it holds no database connection while it waits,
only for each poll's read, one of the read pool's ``CALSTATION_READ_POOL_SIZE``
connections (shared with the lookups and lists) for one primary-key range scan. So the
listeners of a server process add one such read per listener and :data:`POLL_S` to the
read pool's work, and their number is what bounds it: at most
``CALSTATION_EVENT_LISTENERS`` (:class:`Listeners`, 64 by default) per process; one more
is answered 503 with ``Retry-After`` before any read (300 listeners, unbounded, took a
process's lookups' p95 from 11 to 179 ms and its submissions' from 72 to 728 ms). The
stream needs a key only when every read does (``CALSTATION_READ_REQUIRES_KEY``): the
dashboard's browser ``EventSource`` sends no ``Authorization`` header, and the cap, not
a key, is what keeps listeners from crowding out the reads.
"""

import asyncio
import logging
from collections.abc import AsyncIterator
from typing import Annotated

from fastapi import APIRouter, Depends, HTTPException, Request, status
from fastapi.sse import EventSourceResponse
from sqlalchemy.exc import DBAPIError

from api.deps import ReadersDep
from api.errors import RETRY_AFTER_S
from api.responses import json_problems
from api.schemas import RunEvent
from db.store import last_stored, stored_after

log = logging.getLogger(__name__)

#: Seconds between a listener's reads of the runs stored since the last it was sent.
POLL_S = 1.0
#: Most runs read at once.
BATCH = 100

router = APIRouter(tags=["events"])


class Listeners:
    """The event streams a server process serves at once: at most ``cap``."""

    def __init__(self, cap: int) -> None:
        self.cap = cap
        self.open = 0

    def enter(self) -> bool:
        """Take a place for one more listener; False when all ``cap`` are taken."""
        if self.open >= self.cap:
            return False
        self.open += 1
        return True

    def leave(self) -> None:
        """Give a listener's place back (its stream ended)."""
        self.open -= 1


async def _place(request: Request) -> AsyncIterator[None]:
    """A listener's place, held until its stream ends; 503 with ``Retry-After`` when
    every place of this server process is taken."""
    listeners: Listeners = request.app.state.event_listeners
    if not listeners.enter():
        raise HTTPException(
            status.HTTP_503_SERVICE_UNAVAILABLE,
            f"this server process already serves {listeners.cap} event streams "
            "(CALSTATION_EVENT_LISTENERS): retry later",
            headers={"Retry-After": str(RETRY_AFTER_S)},
        )
    try:
        yield
    finally:
        listeners.leave()


#: The 503 of the stream, its ``Retry-After`` described.
_UNAVAILABLE = json_problems(
    503,
    _503="the results database does not answer, or every event-stream place of this "
    "server process is taken (CALSTATION_EVENT_LISTENERS; `Retry-After`)",
)
_UNAVAILABLE[503]["headers"] = {
    "Retry-After": {
        "description": "seconds to wait before asking again (when the places are taken)",
        "schema": {"type": "integer"},
    }
}


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
    responses={**json_problems(413, 422), **_UNAVAILABLE},
    dependencies=[Depends(_place)],
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
