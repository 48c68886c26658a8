"""The end-of-line report, a unit's calibration certificate and the line dashboard.

``GET /api/v1/reports/eol`` (JSON, CSV or HTML), ``GET /api/v1/units/{serial}/certificate``
(HTML: the certificate, or the failure report of a unit on hold) and ``GET /`` (the
dashboard page, following ``GET /api/v1/events``).
"""

from datetime import UTC, datetime
from typing import Annotated, Any, Literal

from fastapi import APIRouter, HTTPException, Path, Query, status
from fastapi.responses import HTMLResponse, Response
from pydantic import BeforeValidator, WithJsonSchema

from api.deps import ReaderDep, ReportPoolDep
from api.errors import invalid
from api.responses import problems
from api.schemas import Problem
from db import RunRepository
from db.holds import held_units
from db.limits_profiles import stored_profiles
from db.reports import eol_report
from station.errors import InputError
from station.quality.figures import EolReport, ReportFilter
from station.records import IDENTIFIER_PATTERN, SERIAL_PATTERN, RunSummary, StoredRun
from station.report.html import certificate_page, dashboard_page
from station.report.period import MAX_LISTED_UNITS, check_order, parse_moment, start_of_day
from station.report.render import MEDIA_TYPES, render
from station.unit_state import counts

#: Units on the dashboard's list, and points on each of its control charts.
DASHBOARD_UNITS = 20
DASHBOARD_CHART_POINTS = 60
#: Units on hold the dashboard lists (the latest).
DASHBOARD_HELD = 50
#: Where the dashboard hears of stored runs (:mod:`api.routes.events`).
EVENTS_PATH = "/api/v1/events"

#: 503: the database is down, a read ran out of time, or the report pool stayed busy.
UNAVAILABLE: dict[int | str, dict[str, Any]] = {
    503: {
        "model": Problem,
        "description": "the database does not answer, a read took longer than the read "
        "timeout, or every report connection stayed busy (`Retry-After`): retry later; "
        "for a report, a shorter range is quicker",
    }
}
router = APIRouter(tags=["reports"], responses=UNAVAILABLE)
dashboard = APIRouter(tags=["reports"])


def _moment(name: str) -> BeforeValidator:
    def parse(text: object) -> object:
        try:
            return parse_moment(text, name=name) if isinstance(text, str) else text
        except InputError as exc:
            raise ValueError(str(exc)) from None

    return BeforeValidator(parse)


_MOMENT_SCHEMA = WithJsonSchema({"type": "string", "examples": ["2026-11-02", "2026-11-02T14:00Z"]})
Since = Annotated[datetime, _moment("from"), _MOMENT_SCHEMA]
Until = Annotated[datetime, _moment("to"), _MOMENT_SCHEMA]
Name = Annotated[str, Query(pattern=IDENTIFIER_PATTERN)]


@router.get(
    "/reports/eol",
    response_class=Response,
    responses={
        200: {
            "model": EolReport,
            "content": {
                MEDIA_TYPES["csv"]: {"schema": {"type": "string"}},
                MEDIA_TYPES["html"]: {"schema": {"type": "string"}},
            },
            "description": "the report in the requested format",
        },
    },
)
async def get_eol_report(
    repository: ReportPoolDep,
    since: Annotated[
        Since | None,
        Query(alias="from", description="start, ISO date or time (UTC if no zone)"),
    ] = None,
    until: Annotated[Until | None, Query(alias="to", description="end (exclusive)")] = None,
    station: Annotated[Name | None, Query(description="only this station")] = None,
    operator: Annotated[Name | None, Query(description="only this operator")] = None,
    lot: Annotated[Name | None, Query(description="only this production lot")] = None,
    format: Literal["json", "csv", "html"] = "json",
    units: Annotated[
        int | None,
        Query(ge=1, le=MAX_LISTED_UNITS, description="list only the latest N units"),
    ] = None,
) -> Response:
    """Yields, failure Pareto, capability, control charts and ship/hold list of a range."""
    try:
        check_order(since, until, names=("from", "to"))
    except InputError as exc:
        raise invalid(("query", "from"), str(exc)) from None
    report_filter = ReportFilter(
        since=since,
        until=until,
        station_id=station,
        operator_id=operator,
        lot=lot,
    )
    body = await repository.run(eol_body, report_filter, units, format)
    return Response(body, media_type=MEDIA_TYPES[format])


def eol_body(
    repository: RunRepository, filter: ReportFilter, units: int | None, format: str
) -> str:
    """The report rendered (in a report process: :mod:`api.report_pool`)."""
    return render(eol_report(repository.session, filter, unit_limit=units), format)


def certificate_run(
    repository: RunRepository, serial: str
) -> tuple[StoredRun, list[RunSummary]] | None:
    """The unit's latest run that counts (an operator's abort does not), as the report's,
    and the unit's runs before it."""
    runs = repository.history(serial)
    counted = [run for run in runs if counts(run)] or runs
    if not counted:
        return None
    run = repository.get(counted[-1].run_id)
    assert run is not None
    return run, runs[: runs.index(counted[-1])]


@router.get(
    "/units/{serial}/certificate",
    response_class=Response,  # 200 is HTML, the errors JSON: each says its own media type
    responses={
        200: {
            "content": {"text/html": {"schema": {"type": "string"}}},
            "description": "the calibration certificate; a unit whose latest run failed gets "
            "its failure report instead (what failed, the values and their limits)",
        },
        **problems(404, _404="no run of this serial number"),
    },
)
async def get_certificate(
    serial: Annotated[str, Path(pattern=SERIAL_PATTERN, description="the unit's serial number")],
    repository: ReaderDep,
) -> HTMLResponse:
    """The unit's calibration certificate: its latest run (aborts aside), coefficients, poses,
    the limits stored with the run's profile and the unit's earlier runs; a failure report
    for a unit whose latest run failed."""
    found = await repository.run(lambda r: certificate_run(r, serial))
    if found is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no calibration run of serial {serial}")
    run, earlier = found
    stored = await repository.run(lambda r: stored_profiles(r.session, [run.limits.sha256]))
    gyro_fit = await repository.run(lambda r: r.latest_gyro_fit(serial))
    profile = stored.get(run.limits.sha256)
    return HTMLResponse(certificate_page(run, profile, datetime.now(UTC), gyro_fit, earlier))


@dashboard.get("/", response_class=HTMLResponse, include_in_schema=False)
async def get_dashboard(repository: ReportPoolDep) -> HTMLResponse:
    """The line dashboard: today's (UTC) counts and yields, latest units, units on hold,
    Pareto, charts; it follows the line's stored runs without a reload."""
    return HTMLResponse(await repository.run(dashboard_body, datetime.now(UTC)))


def dashboard_body(repository: RunRepository, now: datetime) -> str:
    """The dashboard page at ``now`` (in a report process: :mod:`api.report_pool`)."""
    report = eol_report(
        repository.session,
        ReportFilter(since=start_of_day(now)),
        unit_limit=DASHBOARD_UNITS,
        chart_points=DASHBOARD_CHART_POINTS,
        now=now,
    )
    held = held_units(repository.session, DASHBOARD_HELD)
    return dashboard_page(report, held.units, held.total, events=EVENTS_PATH)
