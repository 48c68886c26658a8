"""The end-of-line report, a unit's calibration certificate and the line dashboard.

``GET /api/v1/reports/eol`` (JSON, CSV or HTML), ``GET /api/v1/units/{serial}/certificate``
(HTML: the certificate, or the failure report of a unit on hold) and ``GET /`` (the
dashboard page, following ``GET /api/v1/events``).
"""

import csv
import io
from collections.abc import AsyncIterator, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime, time
from typing import Annotated, Any, Literal

from fastapi import (
    APIRouter,
    Depends,
    File,
    Form,
    HTTPException,
    Path,
    Query,
    Request,
    UploadFile,
    status,
)
from fastapi.responses import HTMLResponse, Response, StreamingResponse
from fastapi.security import HTTPAuthorizationCredentials
from pydantic import BeforeValidator
from sqlalchemy.ext.asyncio import AsyncSession, async_sessionmaker

from api.deps import (
    CredentialsDep,
    ReaderDep,
    ReadersDep,
    ReportPoolDep,
    SessionsDep,
    require_quality,
)
from api.errors import answers_pages, invalid
from api.language import LanguageDep
from api.report_bodies import (
    Pages,
    Plant,
    dashboard_body,
    eol_body,
    failing_runs_body,
    split_body,
)
from api.report_pool import ReportPool
from api.responses import problems
from api.schemas import Problem
from db.report import CHART_POINTS, HEADER, SPLIT_PARAMETERS, SPLIT_RUNS, run_page
from db.store import certificate_inputs, keep_profile, stored_profiles
from station.domain.constants import IDENTIFIER_PATTERN
from station.domain.errors import InputError
from station.domain.i18n import Language
from station.domain.product.laboratory import Laboratory
from station.domain.product.limits import LimitsProfile, parse_profiles, pick_profile
from station.domain.quality.figures import EolReport, ReportFilter
from station.domain.quality.split import SplitBy, SplitReport
from station.domain.record.records import (
    SERIAL_PATTERN,
)
from station.report.period import MAX_LISTED_UNITS, check_order, parse_moment
from station.report.render import MEDIA_TYPES

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


def _blank_is_none(text: object) -> object:
    """An empty field of the report's form means "no filter"."""
    return None if text == "" else text


Blank = BeforeValidator(_blank_is_none)
Name = Annotated[str, Query(pattern=IDENTIFIER_PATTERN)]
Moment = Annotated[
    str, Query(max_length=64, examples=["2026-11-02", "2026-11-02T14:00", "2026-11-02T14:00Z"])
]

#: Units on a page of the report's list.
PAGE_UNITS = 50
#: The most units a page may hold.
MAX_PAGE_UNITS = 1000


async def get_plant_zone(request: Request) -> str:
    """The plant's time zone (``CALSTATION_PLANT_TIMEZONE``)."""
    zone: str = request.app.state.plant_timezone
    return zone


PlantZoneDep = Annotated[str, Depends(get_plant_zone)]


async def get_plant_shifts(request: Request) -> tuple[time, ...]:
    """The plant's shift start times (``CALSTATION_PLANT_SHIFTS``), none by default."""
    shifts: tuple[time, ...] = request.app.state.plant_shifts
    return shifts


PlantShiftsDep = Annotated[tuple[time, ...], Depends(get_plant_shifts)]


async def get_laboratory(request: Request) -> Laboratory:
    """The laboratory its certificates name (``CALSTATION_LABORATORY_FILE``'s
    ``[laboratory]``; none: every field "not configured")."""
    laboratory: Laboratory = request.app.state.laboratory
    return laboratory


LaboratoryDep = Annotated[Laboratory, Depends(get_laboratory)]


async def get_export_page_size(request: Request) -> int:
    """Runs per page of the CSV export (``CALSTATION_EXPORT_PAGE_SIZE``)."""
    size: int = request.app.state.export_page_size
    return size


ExportPageSizeDep = Annotated[int, Depends(get_export_page_size)]


@dataclass(frozen=True)
class Period:
    """The report's filter as the query gives it: ``from``/``to`` without a zone are the
    plant's time; an empty field is no filter; ``from`` must come before ``to``."""

    since: Annotated[
        Moment | None,
        Blank,
        Query(
            alias="from",
            description="start (inclusive), ISO date or time; the plant's "
            "time zone unless one is given",
        ),
    ] = None
    until: Annotated[
        Moment | None, Blank, Query(alias="to", description="end (exclusive), as `from`")
    ] = None
    station: Annotated[Name | None, Blank, Query(description="only this station")] = None
    operator: Annotated[Name | None, Blank, Query(description="only this operator")] = None
    lot: Annotated[Name | None, Blank, Query(description="only this production lot")] = None
    part_number: Annotated[
        Name | None, Blank, Query(description="only this product (its part number)")
    ] = None

    def filter(self, zone: str) -> ReportFilter:
        """The filter, or a 422 naming the bound that is wrong."""
        bounds = []
        for name, text in (("from", self.since), ("to", self.until)):
            try:
                bounds.append(parse_moment(text, name=name, zone=zone) if text else None)
            except InputError as exc:
                raise invalid(("query", name), str(exc)) from None
        try:
            check_order(bounds[0], bounds[1], names=("from", "to"))
        except InputError as exc:
            raise invalid(("query", "from"), str(exc)) from None
        return ReportFilter(
            since=bounds[0],
            until=bounds[1],
            station_id=self.station,
            operator_id=self.operator,
            lot=self.lot,
            part_number=self.part_number,
        )


PeriodDep = Annotated[Period, Depends()]


#: A refused request for the report as HTML is answered with a page saying why (422).
REPORT_TITLE = "End-of-line report"
_REFUSED_PAGE = {
    "content": {MEDIA_TYPES["html"]: {"schema": {"type": "string"}}},
    "description": "a parameter is invalid: JSON (`errors` names each), or, when the "
    "report was asked for as HTML, a page saying why in one line with the form to "
    "correct it",
}
_REPORT_ANSWERS: dict[int | str, dict[str, Any]] = {
    422: {**problems(422)[422], **_REFUSED_PAGE},
    200: {
        "model": EolReport,
        "content": {
            MEDIA_TYPES["csv"]: {"schema": {"type": "string"}},
            MEDIA_TYPES["html"]: {"schema": {"type": "string"}},
        },
        "description": "the report in the requested format",
    },
}
Sha256 = Annotated[str, Query(pattern="^[0-9a-f]{64}$")]
WhatIfId = Annotated[
    Sha256 | None,
    Blank,
    Query(
        description="a what-if's candidate limits profile by its SHA-256, as the what-if "
        "(`POST`) stored it: the report re-judged against it, as that what-if answered; "
        "refused (422) when the runs selected are of more than one product",
    ),
]
Format = Literal["json", "csv", "html"]
Listed = Annotated[
    Literal["held", "all"],
    Query(alias="list", description="the units listed: held ones (latest run failed) or all"),
]
PageSize = Annotated[int, Query(ge=1, le=MAX_PAGE_UNITS, description="units per page of the list")]
PageNumber = Annotated[int, Query(ge=1, le=MAX_LISTED_UNITS, description="page of the list")]
#: The most runs a control chart may plot (the latest of the period).
MAX_CHART_POINTS = 1000
ChartPoints = Annotated[
    int,
    Query(
        ge=10,
        le=MAX_CHART_POINTS,
        description="runs each control chart plots: the latest of the period (and station, "
        "operator, lot, product); its limits come from every run of it",
    ),
]


@router.get("/reports/eol", response_class=Response, responses=_REPORT_ANSWERS)
@answers_pages(REPORT_TITLE, "json")
async def get_eol_report(
    repository: ReportPoolDep,
    reader: ReaderDep,
    period: PeriodDep,
    zone: PlantZoneDep,
    shifts: PlantShiftsDep,
    language: LanguageDep,
    format: Format = "json",
    listed: Listed = "held",
    units: PageSize = PAGE_UNITS,
    page: PageNumber = 1,
    points: ChartPoints = CHART_POINTS,
    what_if: WhatIfId = None,
) -> Response:
    """Yields, trend, failure Pareto, capability, control charts and a page of the held
    (or all) units of a period; with ``what_if``, a stored what-if's candidate limits
    beside them (the link a what-if's page gives)."""
    pages = Pages(held=listed == "held", size=units, offset=(page - 1) * units, points=points)
    plant = Plant(zone, shifts)
    report_filter = period.filter(zone)
    candidate = None
    if what_if is not None:
        stored = await reader.run(lambda r: stored_profiles(r.session, [what_if]))
        if what_if not in stored:
            raise invalid(
                ("query", "what_if"),
                f"no stored limits profile {what_if}: run the what-if with its file again",
            )
        candidate = stored[what_if]
    body = await _report(
        repository, report_filter, pages, format, plant, candidate, candidate is not None, language
    )
    return Response(body, media_type=MEDIA_TYPES[format])


async def _report(
    repository: ReportPool,
    filter: ReportFilter,
    pages: Pages,
    format: str,
    plant: Plant,
    candidate: LimitsProfile | None,
    candidate_kept: bool,
    language: Language = "en",
) -> str:
    """The report's body; a 422 when a ``candidate`` is asked of runs of several products
    (a profile is one product's). ``candidate_kept``: the candidate is stored."""
    try:
        return await repository.run(
            eol_body, filter, pages, format, plant, candidate, candidate_kept, language
        )
    except InputError as exc:
        raise invalid(("query", "part_number"), str(exc)) from None


@router.post(
    "/reports/eol",
    response_class=Response,
    responses={
        **_REPORT_ANSWERS,
        **problems(
            400,
            401,
            403,
            _400="the body is not multipart form data",
            _401="a key was given and it is unknown or revoked",
            _403="a key was given and it is not a quality engineer's",
        ),
        422: {
            **problems(422)[422],
            **_REFUSED_PAGE,
            "description": "a parameter is invalid, or the limits file is not one (not UTF-8, "
            "not TOML, nested too deeply, a profile that is not a table or a bound outside "
            "what its quantity can take): `errors` names `body.limits` and says which; or the "
            "runs selected are of more than one product (a candidate profile is one "
            "product's: `errors` names `query.part_number`); as HTML (the default format) a "
            "page saying why in one line",
        },
    },
    summary="Report with what-if limits",
)
@answers_pages(REPORT_TITLE, "html")
async def post_eol_what_if(
    repository: ReportPoolDep,
    sessions: SessionsDep,
    period: PeriodDep,
    zone: PlantZoneDep,
    shifts: PlantShiftsDep,
    credentials: CredentialsDep,
    language: LanguageDep,
    limits: Annotated[
        UploadFile, File(description="the candidate limits file (TOML, as the station's)")
    ],
    profile: Annotated[
        str | None,
        Blank,
        Form(
            description="the profile of the file to use (default: its only one, or "
            "kxm52-production)"
        ),
    ] = None,
    key: Annotated[
        str | None,
        Blank,
        Form(
            description="a quality key (or the request's bearer key): the candidate profile "
            "is kept by its SHA-256, so `GET /reports/eol?what_if=SHA256` answers this "
            "what-if again; without a key the what-if is answered and nothing is stored"
        ),
    ] = None,
    format: Format = "html",
    listed: Listed = "held",
    units: PageSize = PAGE_UNITS,
    page: PageNumber = 1,
) -> Response:
    """The report of ``GET /reports/eol`` with its runs re-judged against a candidate
    limits profile (uploaded): yields, Pareto and capability beside the current ones, and
    the units whose verdict would flip. No verdict is stored. With a quality key (typed
    into the form or the bearer key) the candidate profile is kept by its SHA-256, so
    ``GET /reports/eol?what_if=SHA256`` (the page's link) answers this what-if again;
    without one, nothing is written."""
    candidate = _candidate(await limits.read(), limits.filename or "limits file", profile)
    if key is not None:
        credentials = HTTPAuthorizationCredentials(scheme="Bearer", credentials=key.strip())
    kept = credentials is not None
    if kept:
        await require_quality(credentials, sessions)
    pages = Pages(held=listed == "held", size=units, offset=(page - 1) * units)
    plant = Plant(zone, shifts)
    body = await _report(
        repository, period.filter(zone), pages, format, plant, candidate, kept, language
    )
    if kept:  # after the report: a refused what-if stores nothing
        async with sessions() as session, session.begin():
            await session.run_sync(keep_profile, candidate)
    return Response(body, media_type=MEDIA_TYPES[format])


def _candidate(content: bytes, shown: str, name: str | None) -> LimitsProfile:
    """The candidate profile of an uploaded limits file, or a 422 saying what is wrong."""
    try:
        return pick_profile(parse_profiles(content.decode("utf-8"), shown), name)
    except UnicodeDecodeError:
        raise invalid(("body", "limits"), f"{shown}: not UTF-8 text") from None
    except InputError as exc:
        raise invalid(("body", "limits"), str(exc)) from None


SPLIT_TITLE = "Analysis by split"
SplitParameter = Annotated[
    str,
    Query(
        pattern=f"^({'|'.join(SPLIT_PARAMETERS)})$",
        description="the parameter: " + ", ".join(SPLIT_PARAMETERS),
    ),
]


@router.get(
    "/reports/split",
    response_class=Response,
    responses={
        200: {
            "model": SplitReport,
            "content": {MEDIA_TYPES["html"]: {"schema": {"type": "string"}}},
            "description": "the parameter's box plots and figures per group (HTML, or JSON "
            f"with `format=json`), from the latest {SPLIT_RUNS} runs of the period and filter",
        },
        422: {**problems(422)[422], **_REFUSED_PAGE},
    },
)
@answers_pages(SPLIT_TITLE, "html", form=False)
async def get_split(
    repository: ReportPoolDep,
    period: PeriodDep,
    zone: PlantZoneDep,
    language: LanguageDep,
    parameter: SplitParameter,
    by: Annotated[SplitBy, Query(description="the run's column the runs are split by")],
    format: Literal["json", "html"] = "html",
) -> Response:
    """A parameter's distribution and capability split by station, lot, operator, fixture
    slot, product or software version: n, mean, sd, quartiles, Tukey whiskers and outliers,
    Cpk and observed ppm per group (the latest runs of the period, bounded)."""
    body = await repository.run(
        split_body, period.filter(zone), parameter, by, format, zone, language
    )
    return Response(body, media_type=MEDIA_TYPES[format])


@router.get(
    "/reports/eol/failures",
    response_class=HTMLResponse,
    responses={
        200: {
            "content": {MEDIA_TYPES["html"]: {"schema": {"type": "string"}}},
            "description": "the latest failing runs of the period whose first failure reason "
            "is `code`: the runs behind a bar of the report's Pareto (a page)",
        },
        422: {**problems(422)[422], **_REFUSED_PAGE},
    },
)
@answers_pages("Failing runs", "html", form=False)
async def get_failing_runs(
    repository: ReportPoolDep,
    period: PeriodDep,
    zone: PlantZoneDep,
    code: Annotated[str, Query(pattern=IDENTIFIER_PATTERN, description="first failure reason")],
    language: LanguageDep,
) -> HTMLResponse:
    """The runs behind a Pareto bar: failing runs of the period (and station, operator,
    lot, product) whose first failure reason is ``code``, the latest first."""
    body = await repository.run(failing_runs_body, period.filter(zone), code, zone, language)
    return HTMLResponse(body)


@router.get(
    "/reports/eol/runs.csv",
    response_class=StreamingResponse,
    responses={
        200: {
            "content": {MEDIA_TYPES["csv"]: {"schema": {"type": "string"}}},
            "description": "one row per run of the period, oldest first, with a header row: "
            + ", ".join(HEADER)
            + ". Streamed: a read that fails after the first page ends the answer without "
            "its last chunk (an incomplete transfer), never as a CSV that looks whole",
        }
    },
)
async def get_run_export(
    period: PeriodDep, zone: PlantZoneDep, readers: ReadersDep, page_size: ExportPageSizeDep
) -> StreamingResponse:
    """Every run of a period (and station, operator, lot, product) as CSV, streamed a page of runs
    at a time: any length of period, in constant memory.

    The first page is read before the answer starts, so a database that does not answer
    is a 503 with its problem body, not a 200 that stops."""
    report_filter = period.filter(zone)
    async with readers() as session:
        first = await session.run_sync(run_page, report_filter, None, page_size)
    return StreamingResponse(
        _csv_pages(readers, report_filter, page_size, first),
        media_type=MEDIA_TYPES["csv"],
        headers={"Content-Disposition": 'attachment; filename="runs.csv"'},
    )


async def _csv_pages(
    readers: async_sessionmaker[AsyncSession],
    filter: ReportFilter,
    page_size: int,
    first: tuple[list[Sequence[Any]], tuple[datetime, int] | None],
) -> AsyncIterator[str]:
    """The export's CSV text, a page of ``page_size`` runs at a time: the ``first`` page
    read, then the pages after it (on a session of its own: it outlives the request's
    handler).

    A read that fails raises on: the server ends the answer without its last chunk, so
    the client sees an incomplete transfer rather than a short CSV."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(HEADER)
    rows, after = first
    writer.writerows(_csv_row(row) for row in rows)
    yield buffer.getvalue()
    if after is None:
        return
    async with readers() as session:
        while after is not None:
            buffer.seek(0)
            buffer.truncate()
            async with session.begin():  # no transaction open while the client reads
                rows, after = await session.run_sync(run_page, filter, after, page_size)
            writer.writerows(_csv_row(row) for row in rows)
            yield buffer.getvalue()


def _csv_row(row: Sequence[object]) -> list[object]:
    """Moments in ISO 8601 (UTC), the rest as they are; no value is an empty cell."""
    return [v.isoformat() if isinstance(v, datetime) else v for v in row]


@router.get(
    "/units/{serial}/certificate",
    response_class=Response,  # 200 is HTML, the errors JSON: each says its own media type
    responses={
        200: {
            "content": {
                "text/html": {"schema": {"type": "string"}},
                "application/pdf": {"schema": {"type": "string", "format": "binary"}},
            },
            "description": "the calibration certificate; a unit whose latest run failed gets "
            "its failure report instead (what failed, the values and their limits), its "
            "title and failures in the reader's language (`lang`, else Accept-Language); "
            "`format=pdf`: the same as a PDF, in the same language",
        },
        **problems(
            400,
            404,
            422,
            _400="`format=pdf` in ko or zh on a server without the Noto Sans CJK font "
            "(Debian's fonts-noto-cjk)",
            _404="no run of this serial number",
            _422="an unknown language or format",
        ),
    },
)
async def get_certificate(
    serial: Annotated[str, Path(pattern=SERIAL_PATTERN, description="the unit's serial number")],
    repository: ReaderDep,
    zone: PlantZoneDep,
    shifts: PlantShiftsDep,
    language: LanguageDep,
    laboratory: LaboratoryDep,
    format: Annotated[
        Literal["html", "pdf"],
        Query(description="html (default), or pdf (in the same language)"),
    ] = "html",
) -> Response:
    """The unit's calibration certificate: its latest run (aborts aside), coefficients, poses,
    the limits stored with the run's profile, its reference (the latest golden-unit check
    of its station in the plant's shift, before it) and the unit's earlier runs; a failure
    report for a unit whose latest run failed. ``lang`` (en, ko, zh; else the
    Accept-Language header's first shipped language, else en): the language of its title
    and its failures (codes and values as stored). ``format=pdf``: the same statements
    as a PDF in the same language (Korean and Chinese with the Noto Sans CJK font; a
    server without it answers 400 naming the package)."""
    found = await repository.run(lambda r: certificate_inputs(r, serial, zone, shifts))
    if found is None:
        raise HTTPException(status.HTTP_404_NOT_FOUND, f"no calibration run of serial {serial}")
    from station.report.certificate_document import certificate_document

    document = certificate_document(found, format, datetime.now(UTC), zone, language, laboratory)
    if format == "pdf":
        return Response(document, media_type="application/pdf")
    return HTMLResponse(document)


@dashboard.get("/", response_class=HTMLResponse, include_in_schema=False)
async def get_dashboard(
    repository: ReportPoolDep, zone: PlantZoneDep, language: LanguageDep
) -> HTMLResponse:
    """The line dashboard: the plant's today: counts and yields, latest units, units on
    hold, Pareto, charts; it follows the line's stored runs without a reload."""
    return HTMLResponse(await repository.run(dashboard_body, datetime.now(UTC), zone, language))
