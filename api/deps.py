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

from db import RunRepository
from db.units import UnitLookups

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
    """The factory of autocommit sessions (for reads)."""
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


async def get_reader(readers: ReadersDep) -> AsyncIterator[Repository]:
    """A repository on an autocommit session, for read-only requests."""
    async with readers() as session:
        yield Repository(session)


RepositoryDep = Annotated[Repository, Depends(get_repository)]
ReaderDep = Annotated[Repository, Depends(get_reader)]

_bearer = HTTPBearer(
    auto_error=False,
    description="A station API key (`calstation keys create --station ID`).",
)
CredentialsDep = Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)]


async def require_station(credentials: CredentialsDep, readers: ReadersDep) -> str:
    """The station whose API key authorises the request; 401 without a valid key."""
    if credentials is None:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "a station API key is required: 'Authorization: Bearer <key>'",
            headers={"WWW-Authenticate": "Bearer"},
        )
    async with readers() as session:
        station = await Repository(session).run(
            lambda repository: repository.station_for_key(credentials.credentials)
        )
    if station is None:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "unknown or revoked API key",
            headers={"WWW-Authenticate": "Bearer"},
        )
    return station


StationDep = Annotated[str, Depends(require_station)]
