"""``/api/v1/runs``: list and read runs; stations submit theirs."""

from typing import Annotated
from uuid import UUID

from fastapi import APIRouter, Depends, HTTPException, Query, Response, status
from pydantic import AwareDatetime

from api.deps import RepositoryDep, StationDep, require_reader
from api.schemas import Problem, RunList
from api.verification import check_coefficients
from db import RunQuery
from db.repository import MAX_PAGE
from station.records import SERIAL_PATTERN, RunRecord, StoredRun, Verdict

router = APIRouter(prefix="/runs", tags=["runs"])


@router.get("", dependencies=[Depends(require_reader)])
def list_runs(
    repository: RepositoryDep,
    serial: Annotated[str | None, Query(pattern=SERIAL_PATTERN)] = None,
    station_id: Annotated[str | None, Query(max_length=64)] = None,
    verdict: Verdict | None = None,
    since: Annotated[AwareDatetime | None, Query(description="started at or after")] = None,
    until: Annotated[AwareDatetime | None, Query(description="started before")] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_PAGE)] = 100,
    cursor: Annotated[str | None, Query(max_length=200)] = None,
) -> RunList:
    """Runs matching every given filter, newest first, one page at a time."""
    page = repository.list_runs(
        RunQuery(
            serial=serial,
            station_id=station_id,
            verdict=verdict,
            since=since,
            until=until,
            limit=limit,
            cursor=cursor,
        )
    )
    return RunList(data=page.runs, count=len(page.runs), next_cursor=page.next_cursor)


@router.get(
    "/{run_id}",
    dependencies=[Depends(require_reader)],
    responses={404: {"model": Problem}},
)
def get_run(run_id: UUID, repository: RepositoryDep) -> StoredRun:
    """One run with every pose."""
    run = repository.get(run_id)
    if run is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no run {run_id}")
    return run


@router.post(
    "",
    status_code=status.HTTP_201_CREATED,
    responses={
        200: {"model": StoredRun, "description": "already stored: the stored run"},
        401: {"model": Problem},
        403: {"model": Problem},
        409: {"model": Problem, "description": "same run UUID, different content"},
        413: {"model": Problem},
        422: {"model": Problem, "description": "invalid, or the poses give other coefficients"},
    },
)
def submit_run(
    record: RunRecord, station: StationDep, repository: RepositoryDep, response: Response
) -> StoredRun:
    """Store a station's run; a retry of a stored run returns it (200) unchanged."""
    if record.station_id != station:
        raise HTTPException(
            status.HTTP_403_FORBIDDEN,
            f"this API key belongs to station {station}, the run to {record.station_id}",
        )
    check_coefficients(record)
    with repository.session.begin():
        outcome = repository.submit(record)
    response.headers["Location"] = f"/api/v1/runs/{record.run_id}"
    if not outcome.created:
        response.status_code = status.HTTP_200_OK
    return outcome.run
