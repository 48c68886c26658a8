"""``GET /units/{serial}``: a unit's page (HTML), where every serial on every page links.

The unit's every run, oldest first (verdict, failure reasons with their values and
limits, coefficients, gyro bias, station, operator, time), links to each run's record and
to its certificate or failure report. A path of its own: ``GET /api/v1/units/{serial}``
stays the unit's JSON. An unknown serial is a 404 page; a serial that is not one
(``station.domain.record.records.SERIAL_PATTERN``) a 422, as everywhere in the API.
"""

from datetime import UTC, datetime
from typing import Annotated, Literal

from fastapi import APIRouter, Form, HTTPException, Path, Query, Response, status
from fastapi.responses import HTMLResponse, RedirectResponse
from fastapi.security import HTTPAuthorizationCredentials
from pydantic import BeforeValidator

from api.deps import ReaderDep, ReportPoolDep, RepositoryDep, SessionsDep, require_quality
from api.errors import answers_pages
from api.language import LanguageDep
from api.responses import problems
from api.routes.reports import PlantZoneDep
from api.routes.reviews import store_review
from api.routes.units import SerialPath
from api.schemas import ReviewForm
from db import ReviewRefusedError, RunRepository
from db.report import CYCLE_RUNS, station_health
from station.domain.constants import IDENTIFIER_PATTERN
from station.domain.i18n import Language
from station.domain.quality.station_health import StationHealth
from station.domain.record.records import (
    SERIAL_PATTERN,
)

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
    serial: SerialPath, repository: ReaderDep, zone: PlantZoneDep, language: LanguageDep
) -> HTMLResponse:
    """The unit's page: its state, every run, links to each record and to its certificate."""
    from station.report import html

    runs = await repository.run(lambda r: r.history(serial))
    if not runs:
        return HTMLResponse(
            html.unknown_unit_page(serial, language),
            status_code=status.HTTP_404_NOT_FOUND,
        )
    reviews = await repository.run(lambda r: r.reviews(serial))
    return HTMLResponse(html.unit_page(runs, datetime.now(UTC), zone, reviews, language))


StationPath = Annotated[
    str, Path(pattern=IDENTIFIER_PATTERN, description="the station's identifier")
]


@router.get(
    "/stations/{station_id}",
    response_class=Response,
    responses={
        200: {
            "model": StationHealth,
            "content": _HTML,
            "description": "the station's health: golden-unit checks against their baseline, "
            "drift warnings, cycle times, versions in use (HTML, or JSON with `format=json`)",
        },
        404: {"content": _HTML, "description": "no run of this station is stored (a page)"},
        **problems(422),
    },
)
async def get_station_page(
    station_id: StationPath,
    repository: ReportPoolDep,
    zone: PlantZoneDep,
    language: LanguageDep,
    format: Literal["json", "html"] = "html",
) -> Response:
    """A station's health page: its latest golden-unit checks over time against their
    baseline, drift warnings, the cycle time distribution of its latest runs and the
    software and limits versions in use."""
    from station.report import html

    health = await repository.run(station_health_of, station_id)
    if health is None:
        return HTMLResponse(
            html.unknown_station_page(station_id, language),
            status_code=status.HTTP_404_NOT_FOUND,
        )
    if format == "json":
        return Response(health.model_dump_json(indent=2), media_type="application/json")
    return HTMLResponse(html.station_page(health, zone, CYCLE_RUNS, language))


def station_health_of(repository: RunRepository, station_id: str) -> StationHealth | None:
    """The station's health (in a report process: :mod:`api.report_pool`)."""
    return station_health(repository.session, station_id)


REVIEW_TITLE = "Review of a unit on hold"
_REVIEW_PAGE = {"content": _HTML}


@router.post(
    "/units/{serial}/reviews",
    response_class=HTMLResponse,
    responses={
        303: {"description": "the review is stored: the unit's page, at its reviews"},
        401: {**_REVIEW_PAGE, "description": "no key typed, or an unknown or revoked one"},
        403: {**_REVIEW_PAGE, "description": "the key is not a quality engineer's"},
        409: {
            **_REVIEW_PAGE,
            "description": "the unit is not on hold, or the run is not its latest",
        },
        422: {**_REVIEW_PAGE, "description": "a field is missing or invalid (a page)"},
    },
)
@answers_pages(REVIEW_TITLE, "html", form=False)
async def post_unit_review(
    serial: SerialPath,
    form: Annotated[ReviewForm, Form()],
    sessions: SessionsDep,
    repository: RepositoryDep,
    language: LanguageDep,
) -> Response:
    """The review form of a held unit's page: the review of ``POST
    /api/v1/units/{serial}/reviews``, with the quality key typed into the form checked as
    that route checks its bearer key. Refused: a page saying why in one line."""
    try:
        if not form.key.strip():
            raise HTTPException(
                status.HTTP_401_UNAUTHORIZED,
                "a quality key is required: type yours into the form "
                "(calstation keys create --quality ID)",
            )
        credentials = HTTPAuthorizationCredentials(scheme="Bearer", credentials=form.key.strip())
        reviewer = await require_quality(credentials, sessions)
        await store_review(serial, form, reviewer, repository)
    except HTTPException as exc:
        return _refused(exc.status_code, str(exc.detail), language)
    except ReviewRefusedError as exc:
        return _refused(status.HTTP_409_CONFLICT, str(exc), language)
    return RedirectResponse(f"/units/{serial}#reviews", status_code=status.HTTP_303_SEE_OTHER)


def _refused(status_code: int, message: str, language: Language) -> HTMLResponse:
    from station.report import html

    page = html.problem_page(REVIEW_TITLE, message, language=language)
    return HTMLResponse(page, status_code=status_code)


#: The most serials a search lists (type more of the serial for fewer).
FOUND_SERIALS = 50
SEARCH_TITLE = "Find a unit"


def _stripped(text: object) -> object:
    """A serial as typed or pasted: without the spaces around it."""
    return text.strip() if isinstance(text, str) else text


SearchQuery = Annotated[
    str,
    BeforeValidator(_stripped),
    Query(
        pattern=SERIAL_PATTERN,
        description="a serial number, or its beginning (letters, digits, . _ -)",
    ),
]


@router.get(
    "/search",
    response_class=Response,
    responses={
        200: {"content": _HTML, "description": "the units whose serial begins so (a page)"},
        303: {"description": "the one unit of this serial: its page (`Location`)"},
        404: {"content": _HTML, "description": "no unit's serial begins so (a page)"},
        422: {
            "content": _HTML,
            "description": "not a serial number or its beginning (a page saying why)",
        },
    },
)
@answers_pages(SEARCH_TITLE, "html", form=False)
async def search_units(
    serial: SearchQuery, repository: ReaderDep, language: LanguageDep
) -> Response:
    """The search box of every page: the unit of this serial number (its page), or the
    units whose serial begins so."""
    from station.report import html

    found = await repository.run(lambda r: r.serials(serial, FOUND_SERIALS + 1))
    if serial in found or len(found) == 1:
        exact = serial if serial in found else found[0]
        return RedirectResponse(f"/units/{exact}", status_code=status.HTTP_303_SEE_OTHER)
    if not found:
        return HTMLResponse(
            html.no_serial_page(SEARCH_TITLE, serial, language),
            status_code=status.HTTP_404_NOT_FOUND,
        )
    more = len(found) > FOUND_SERIALS
    return HTMLResponse(html.found_page(serial, found[:FOUND_SERIALS], more, language))
