"""``GET /healthz``: 200 when the database answers."""

from fastapi import APIRouter

from api.deps import RepositoryDep
from api.schemas import Health

router = APIRouter(tags=["health"])


@router.get("/healthz", responses={503: {"description": "the database does not answer"}})
def healthz(repository: RepositoryDep) -> Health:
    """The server is up and its database answers."""
    repository.ping()
    return Health(status="ok", database=repository.session.get_bind().dialect.name)
