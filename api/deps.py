"""Dependencies of the routes, as ``Annotated`` aliases so signatures read as plain data."""

from collections.abc import Iterator
from typing import Annotated

from fastapi import Depends, HTTPException, Request, status
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer

from api.settings import ApiSettings
from db import Database, RunRepository


def get_settings(request: Request) -> ApiSettings:
    """The settings the app was created with."""
    settings: ApiSettings = request.app.state.settings
    return settings


def get_database(request: Request) -> Database:
    """The database opened at start-up."""
    database: Database = request.app.state.database
    return database


SettingsDep = Annotated[ApiSettings, Depends(get_settings)]
DatabaseDep = Annotated[Database, Depends(get_database)]


def get_repository(database: DatabaseDep) -> Iterator[RunRepository]:
    """A repository on a session that lives as long as the request."""
    with database.session() as session:
        yield RunRepository(session)


RepositoryDep = Annotated[RunRepository, Depends(get_repository)]

_bearer = HTTPBearer(
    auto_error=False,
    description="A station API key (`calstation keys create --station ID`).",
)
CredentialsDep = Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)]


def require_station(credentials: CredentialsDep, database: DatabaseDep) -> str:
    """The station whose API key authorises the request; 401 without a valid key."""
    if credentials is None:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "a station API key is required: 'Authorization: Bearer <key>'",
            headers={"WWW-Authenticate": "Bearer"},
        )
    # A short session of its own: the submission's transaction starts with its write.
    with database.session() as session:
        station = RunRepository(session).station_for_key(credentials.credentials)
    if station is None:
        raise HTTPException(
            status.HTTP_401_UNAUTHORIZED,
            "unknown or revoked API key",
            headers={"WWW-Authenticate": "Bearer"},
        )
    return station


StationDep = Annotated[str, Depends(require_station)]


def require_reader(
    settings: SettingsDep, credentials: CredentialsDep, database: DatabaseDep
) -> None:
    """Read endpoints are open unless ``read_requires_key`` is set."""
    if settings.read_requires_key:
        require_station(credentials, database)
