"""Dependencies of the routes, as ``Annotated`` aliases so signatures read as plain data.

The routes are ``async``: each request's queries run through
:meth:`AsyncSession.run_sync` on the one synchronous :class:`db.RunRepository`, in the
event loop's own thread (no thread-pool hop per request).
"""

from collections.abc import AsyncIterator, Callable
from typing import Annotated, TypeVar

from fastapi import Depends, HTTPException, Request, status
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from sqlalchemy.ext.asyncio import AsyncSession, async_sessionmaker

from api.report_pool import ReportPool
from db import RunRepository
from db.store import KeyHolder, UnitLookups

T = TypeVar("T")


class Repository:
    """The run repository of one request's session."""

    def __init__(self, session: AsyncSession) -> None:
        self.session = session

    async def run(self, work: Callable[[RunRepository], T]) -> T:
        """``work(repository)`` on this session."""
        return await self.session.run_sync(lambda session: work(RunRepository(session)))


async def get_sessions(request: Request) -> async_sessionmaker[AsyncSession]:
    """The factory of transactional sessions (for writes)."""
    sessions: async_sessionmaker[AsyncSession] = request.app.state.sessions
    return sessions


async def get_readers(request: Request) -> async_sessionmaker[AsyncSession]:
    """The factory of read sessions (each transaction bounded by the read timeout)."""
    readers: async_sessionmaker[AsyncSession] = request.app.state.readers
    return readers


async def get_unit_lookups(request: Request) -> UnitLookups:
    """The server process's reader of units' current calibrations."""
    lookups: UnitLookups = request.app.state.unit_lookups
    return lookups


SessionsDep = Annotated[async_sessionmaker[AsyncSession], Depends(get_sessions)]
ReadersDep = Annotated[async_sessionmaker[AsyncSession], Depends(get_readers)]
UnitLookupsDep = Annotated[UnitLookups, Depends(get_unit_lookups)]


async def get_repository(sessions: SessionsDep) -> AsyncIterator[Repository]:
    """A repository on a transactional session that lives as long as the request."""
    async with sessions() as session:
        yield Repository(session)


class Reader(Repository):
    """The run repository of one request's read session: each :meth:`run` a transaction of
    its own, which carries the read timeout (``SET LOCAL``, :mod:`db.timeouts`) and ends
    with it, so that no transaction stays open while the request awaits anything else
    (through a pooler in transaction mode it would hold a PostgreSQL connection)."""

    async def run(self, work: Callable[[RunRepository], T]) -> T:
        """``work(repository)`` in a transaction of its own on this session."""
        async with self.session.begin():
            return await super().run(work)


async def get_reader(readers: ReadersDep) -> AsyncIterator[Repository]:
    """A repository for read-only requests, a transaction for each of its reads."""
    async with readers() as session:
        yield Reader(session)


RepositoryDep = Annotated[Repository, Depends(get_repository)]
ReaderDep = Annotated[Repository, Depends(get_reader)]


async def get_report_pool(request: Request) -> ReportPool:
    """The report pool: the end-of-line report and the dashboard, apart from the rest."""
    pool: ReportPool = request.app.state.report_pool
    return pool


#: Heavy key-less reads; ``await reports.run(work)`` as on a :class:`Repository`.
ReportPoolDep = Annotated[ReportPool, Depends(get_report_pool)]

_bearer = HTTPBearer(
    auto_error=False,
    description=(
        "An API key: a station's (`calstation keys create --station ID`) stores that "
        "station's runs, a lab's (`calstation keys create --lab ID`) stores gyro fits, "
        "a quality engineer's (`calstation keys create --quality ID`) reviews units on hold."
    ),
)
CredentialsDep = Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)]


async def _key_holder(
    credentials: HTTPAuthorizationCredentials | None, sessions: async_sessionmaker[AsyncSession]
) -> KeyHolder:
    """The holder of the request's API key (looked up on ``sessions``); 401 without one."""
    if credentials is None:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "an API key is required: 'Authorization: Bearer <key>'",
            headers={"WWW-Authenticate": "Bearer"},
        )
    async with sessions() as session:
        holder = await Repository(session).run(
            lambda repository: repository.key_holder(credentials.credentials)
        )
    if holder is None:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "unknown or revoked API key",
            headers={"WWW-Authenticate": "Bearer"},
        )
    return holder


async def require_key(credentials: CredentialsDep, readers: ReadersDep) -> KeyHolder:
    """Any valid API key (reads, when the server wants a key for them)."""
    return await _key_holder(credentials, readers)


def _holder_in_scope(holder: KeyHolder, scope: str, needs: str) -> str:
    """``holder``'s name when its key is of ``scope``; else a 403 naming the key's own
    scope and holder, and what ``needs`` (what the request stores) takes."""
    if holder.scope != scope:
        raise HTTPException(
            status.HTTP_403_FORBIDDEN,
            f"this API key belongs to {holder.scope} {holder.holder}: {needs} "
            f"(calstation keys create --{scope} ID)",
        )
    return holder.holder


async def require_station(credentials: CredentialsDep, sessions: SessionsDep) -> str:
    """The station whose key authorises a submission of runs; 403 for any other key.

    Looked up on the submissions' own pool: report readers never hold up a station.
    """
    holder = await _key_holder(credentials, sessions)
    return _holder_in_scope(holder, "station", "runs need their station's key")


async def require_lab(credentials: CredentialsDep, sessions: SessionsDep) -> str:
    """The lab whose key authorises storing a gyro fit; 403 for any other key."""
    holder = await _key_holder(credentials, sessions)
    return _holder_in_scope(holder, "lab", "gyro fits need a lab key")


async def require_quality(credentials: CredentialsDep, sessions: SessionsDep) -> str:
    """The quality engineer whose key authorises a review of a unit on hold or keeps a
    what-if's candidate profile; 403 for any other key."""
    holder = await _key_holder(credentials, sessions)
    return _holder_in_scope(
        holder, "quality", "reviews of units on hold and kept what-ifs need a quality key"
    )


StationDep = Annotated[str, Depends(require_station)]
LabDep = Annotated[str, Depends(require_lab)]
QualityDep = Annotated[str, Depends(require_quality)]
