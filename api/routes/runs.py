"""``/api/v1/runs``: list and read runs; stations submit theirs."""

import logging
from typing import Annotated
from uuid import UUID

from fastapi import APIRouter, Header, HTTPException, Query, Request, Response, status

from api.deps import ReaderDep, RepositoryDep, StationDep
from api.errors import invalid
from api.metrics import get_metrics, refuse
from api.responses import json_response, problems
from api.schemas import RunList
from api.verification import CalibrationMismatchError, check_coefficients, counts_beyond_sensor
from db import RunQuery
from db.store import MAX_PAGE
from station.domain.constants import IDENTIFIER_PATTERN, PART_NUMBER_PATTERN
from station.domain.errors import InputError
from station.domain.product.limits import profile_of
from station.domain.record.outbox_report import OUTBOX_HEADER, parse_outbox_header
from station.domain.record.records import (
    SERIAL_PATTERN,
    RunRecord,
    StoredRun,
    UtcDatetime,
    Verdict,
)
from station.domain.sensors.record_bounds import RUN_YEARS, implausible_run_time

log = logging.getLogger(__name__)

#: Reads (open, or key-protected by the app's settings).
router = APIRouter(prefix="/runs", tags=["runs"])
#: Submissions: always need a station key.
submissions = APIRouter(prefix="/runs", tags=["runs"])


@router.get(
    "", response_model=RunList, responses=problems(400, _400="a cursor this server never gave")
)
async def list_runs(
    repository: ReaderDep,
    serial: Annotated[str | None, Query(pattern=SERIAL_PATTERN)] = None,
    station_id: Annotated[str | None, Query(pattern=IDENTIFIER_PATTERN)] = None,
    lot: Annotated[
        str | None, Query(pattern=IDENTIFIER_PATTERN, description="the unit's production lot")
    ] = None,
    part_number: Annotated[
        str | None, Query(pattern=PART_NUMBER_PATTERN, description="the unit's product")
    ] = None,
    verdict: Verdict | None = None,
    since: Annotated[UtcDatetime | None, Query(description="started at or after")] = None,
    until: Annotated[UtcDatetime | None, Query(description="started before")] = None,
    limit: Annotated[int, Query(ge=1, le=MAX_PAGE)] = 100,
    cursor: Annotated[str | None, Query(max_length=200, pattern=r"^[A-Za-z0-9_=-]*$")] = None,
) -> Response:
    """Runs matching every given filter, newest first, one page at a time."""
    query = RunQuery(
        serial=serial,
        station_id=station_id,
        lot=lot,
        part_number=part_number,
        verdict=verdict,
        since=since,
        until=until,
        limit=limit,
        cursor=cursor,
    )
    page = await repository.run(lambda r: r.list_runs(query))
    return json_response(
        RunList(data=page.runs, count=len(page.runs), next_cursor=page.next_cursor)
    )


@router.get("/{run_id}", response_model=StoredRun, responses=problems(404, _404="no such run"))
async def get_run(run_id: UUID, repository: ReaderDep) -> Response:
    """One run with every pose."""
    run = await repository.run(lambda r: r.get(run_id))
    if run is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no run {run_id}")
    return json_response(run)


@submissions.post(
    "",
    status_code=status.HTTP_201_CREATED,
    response_model=StoredRun,
    responses={
        200: {"model": StoredRun, "description": "already stored: the stored run"},
        **problems(
            400,
            401,
            403,
            409,
            422,
            _403="the API key belongs to another station",
            _422="invalid (each offending field named: a limits profile that does not hash to "
            "its sha256, or holds a bound outside what its quantity can take, is one; a "
            "`started_at` or `finished_at` outside the years "
            f"{RUN_YEARS[0]}…{RUN_YEARS[1]} is another, a pose mean beyond the ADC range "
            "of its product's sensor a third), or the poses give other "
            "coefficients",
        ),
    },
)
async def submit_run(
    record: RunRecord,
    station: StationDep,
    repository: RepositoryDep,
    request: Request,
    outbox: Annotated[
        str | None,
        Header(
            alias=OUTBOX_HEADER,
            description="the station's outbox as it sends this run, kept as its latest "
            "report (the `[[outbox]]` alert rule): `queued=N; oldest_s=N; set_aside=N`, "
            "runs queued behind this one, whole seconds the oldest of them has waited, "
            "files set aside (refused, unreadable); a station that sends none, or one "
            "that does not parse (logged), is stored as before without a report",
            examples=["queued=12; oldest_s=5400; set_aside=1"],
        ),
    ] = None,
) -> Response:
    """Store a station's run; a retry of a stored run returns it (200) unchanged."""
    if record.station_id != station:
        refuse(request, "wrong_station")
        raise HTTPException(
            status.HTTP_403_FORBIDDEN,
            f"this API key belongs to station {station}, the run to {record.station_id}",
        )
    for field, moment in (("started_at", record.started_at), ("finished_at", record.finished_at)):
        why = implausible_run_time(moment)
        if why is not None:
            refuse(request, "implausible_time")
            raise invalid(("body", field), why)
    beyond = counts_beyond_sensor(record)
    if beyond is not None:
        raise invalid(("body", "poses"), beyond)
    report = None
    if outbox is not None:
        try:
            report = parse_outbox_header(outbox)
        except InputError as exc:
            # Monitoring, not the record: a good run is never refused for it (the station
            # would set the run aside); its report is left out and the log says why.
            log.warning(
                "run %s from %s stored without its outbox report: %s", record.run_id, station, exc
            )
    try:
        profile_of(record.limits)
    except InputError as exc:
        refuse(request, "limits_profile")
        raise invalid(("body", "limits", "profile"), str(exc)) from None
    try:
        check_coefficients(record)
    except CalibrationMismatchError as exc:
        refuse(request, "calibration_mismatch")
        log.warning(
            "run %s serial=%s station=%s refused: %s", record.run_id, record.serial, station, exc
        )
        raise
    async with repository.session.begin():
        outcome = await repository.run(lambda r: r.submit(record, outbox=report))
    if outcome.created:  # committed: a retry of a stored run is not counted again
        stored = get_metrics(request).runs_stored
        stored.labels(station, record.verdict, record.part_number).inc()
    log.info(
        "run %s serial=%s station=%s verdict=%s %s",
        record.run_id,
        record.serial,
        station,
        record.verdict,
        "stored" if outcome.created else "already stored",
    )
    answer = json_response(
        outcome.run,
        status.HTTP_201_CREATED if outcome.created else status.HTTP_200_OK,
    )
    answer.headers["Location"] = f"/api/v1/runs/{record.run_id}"
    return answer
