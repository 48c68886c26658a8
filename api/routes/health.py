"""``GET /healthz``: 200 when the database answers."""

from fastapi import APIRouter

from api.deps import ReaderDep
from api.responses import problems
from api.schemas import Health

router = APIRouter(tags=["health"])


@router.get("/healthz", responses=problems(503, _503="the database does not answer"))
async def healthz(repository: ReaderDep) -> Health:
    """The server is up and its database answers."""
    dialect = await repository.run(lambda r: r.ping())
    return Health(status="ok", database=dialect)
