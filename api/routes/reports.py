"""The end-of-line report, a unit's calibration certificate and the line dashboard.

``GET /api/v1/reports/eol`` (JSON, CSV or HTML), ``GET /api/v1/units/{serial}/certificate``
(HTML) and ``GET /`` (the dashboard page, reloading itself).
"""

from datetime import UTC, datetime
from typing import Annotated, Literal

from fastapi import APIRouter, HTTPException, Path, Query, status
from fastapi.responses import HTMLResponse, Response

from api.deps import ReaderDep, RepositoryDep
from api.schemas import Problem
from db import RunRepository
from db.reports import eol_report
from station.limits import load_profiles
from station.records import SERIAL_PATTERN, StoredRun
from station.report.bounds import choose_profile
from station.report.html import certificate_page, dashboard_page
from station.report.model import ReportFilter
from station.report.period import parse_moment, start_of_day
from station.report.render import MEDIA_TYPES, render
from station.unit_state import counts

#: Units on the dashboard's list, and points on each of its control charts.
DASHBOARD_UNITS = 20
DASHBOARD_CHART_POINTS = 60

router = APIRouter(tags=["reports"])
dashboard = APIRouter(tags=["reports"])


@router.get(
    "/reports/eol",
    responses={
        200: {
            "content": {MEDIA_TYPES["csv"]: {}, MEDIA_TYPES["html"]: {}},
            "description": "the report in the requested format",
        },
        400: {"model": Problem, "description": "a bound is not a date or time"},
    },
)
async def get_eol_report(
    repository: RepositoryDep,
    since: Annotated[
        str | None, Query(alias="from", description="start, ISO date or time (UTC if no zone)")
    ] = None,
    until: Annotated[str | None, Query(alias="to", description="end (exclusive)")] = None,
    station: Annotated[str | None, Query(description="only this station")] = None,
    operator: Annotated[str | None, Query(description="only this operator")] = None,
    lot: Annotated[str | None, Query(description="only this production lot")] = None,
    format: Literal["json", "csv", "html"] = "json",
    units: Annotated[int | None, Query(ge=1, description="list only the latest N units")] = None,
) -> Response:
    """Yields, failure Pareto, capability, control charts and ship/hold list of a range."""
    report_filter = ReportFilter(
        since=parse_moment(since, name="from") if since else None,
        until=parse_moment(until, name="to") if until else None,
        station_id=station,
        operator_id=operator,
        lot=lot,
    )
    # A transactional session: the report sets its PostgreSQL planner options locally.
    report = await repository.run(lambda r: eol_report(r.session, report_filter, unit_limit=units))
    return Response(render(report, format), media_type=MEDIA_TYPES[format])


def _latest_run(repository: RunRepository, serial: str) -> StoredRun | None:
    """The unit's latest run that counts (an operator's abort does not), as the report's."""
    runs = repository.history(serial)
    counted = [run for run in runs if counts(run)] or runs
    return repository.get(counted[-1].run_id) if counted else None


@router.get(
    "/units/{serial}/certificate",
    response_class=HTMLResponse,
    responses={404: {"model": Problem, "description": "no run of this serial number"}},
)
async def get_certificate(
    serial: Annotated[str, Path(pattern=SERIAL_PATTERN, description="the unit's serial number")],
    repository: ReaderDep,
) -> HTMLResponse:
    """The unit's calibration certificate: its latest run (aborts aside), coefficients, poses,
    limits."""
    run = await repository.run(lambda r: _latest_run(r, serial))
    if run is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no calibration run of serial {serial}")
    profile, _ = choose_profile([run.limits], load_profiles())
    gyro_fit = await repository.run(lambda r: r.latest_gyro_fit(serial))
    return HTMLResponse(certificate_page(run, profile, datetime.now(UTC), gyro_fit))


@dashboard.get("/", response_class=HTMLResponse, include_in_schema=False)
async def get_dashboard(repository: RepositoryDep) -> HTMLResponse:
    """The line dashboard: today's (UTC) counts and yields, latest units, Pareto, charts."""
    now = datetime.now(UTC)
    report = await repository.run(
        lambda r: eol_report(
            r.session,
            ReportFilter(since=start_of_day(now)),
            unit_limit=DASHBOARD_UNITS,
            chart_points=DASHBOARD_CHART_POINTS,
            now=now,
        )
    )
    return HTMLResponse(dashboard_page(report))
