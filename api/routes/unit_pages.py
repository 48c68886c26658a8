"""``GET /units/{serial}``: a unit's page (HTML), where every serial on every page links.

The unit's every run, oldest first (verdict, failure reasons with their values and
limits, coefficients, gyro bias, station, operator, time), links to each run's record and
to its certificate or failure report. A path of its own: ``GET /api/v1/units/{serial}``
stays the unit's JSON. An unknown serial is a 404 page; a serial that is not one
(``station.domain.records.SERIAL_PATTERN``) a 422, as everywhere in the API.
"""

from datetime import UTC, datetime

from fastapi import APIRouter, Response, status
from fastapi.responses import HTMLResponse

from api.deps import ReaderDep
from api.responses import problems
from api.routes.reports import PlantZoneDep
from api.routes.units import SerialPath
from station.report.html import not_found_page, unit_page

router = APIRouter(tags=["pages"])

_HTML = {"text/html": {"schema": {"type": "string"}}}


@router.get(
    "/units/{serial}",
    response_class=Response,  # 200 and 404 are HTML, the errors JSON: each says its own
    responses={
        200: {"content": _HTML, "description": "the unit's page"},
        404: {"content": _HTML, "description": "no run of this serial number (a page)"},
        **problems(422),
    },
)
async def get_unit_page(
    serial: SerialPath, repository: ReaderDep, zone: PlantZoneDep
) -> HTMLResponse:
    """The unit's page: its state, every run, links to each record and to its certificate."""
    runs = await repository.run(lambda r: r.history(serial))
    if not runs:
        return HTMLResponse(
            not_found_page(f"No calibration run of serial {serial} is stored."),
            status_code=status.HTTP_404_NOT_FOUND,
        )
    return HTMLResponse(unit_page(runs, datetime.now(UTC), zone))
