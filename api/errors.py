"""Every refused request ends as a 4xx with one clear ``detail`` line (never a 5xx).

Answer bodies are ``{"detail": "..."}`` (:class:`api.schemas.Problem`); every 422 adds
``errors``, one entry per offending field with its location
(:class:`api.schemas.ValidationProblem`), whether pydantic, a route's own check
(:func:`invalid`) or the server's solve refused it. :mod:`api.responses` documents them.
"""

import logging
from collections.abc import Awaitable, Callable, Sequence
from typing import Any, TypeVar

from fastapi import FastAPI, Request, Response, status
from fastapi.exceptions import RequestValidationError
from fastapi.responses import HTMLResponse, JSONResponse
from sqlalchemy.exc import OperationalError

from api.report_pool import ReadTimeoutError, ReportsBusyError
from api.verification import CalibrationMismatchError
from db import (
    DatabaseUnavailableError,
    ReviewRefusedError,
    RunConflictError,
    SchemaOutOfDateError,
)
from db.timeouts import is_statement_timeout
from station.domain.errors import InputError

log = logging.getLogger(__name__)

#: How many field errors the one-line ``detail`` names.
DETAIL_FIELDS = 3


def _location(loc: tuple[int | str, ...]) -> str:
    return ".".join(str(part) for part in loc)


def invalid(loc: tuple[str, ...], message: str) -> RequestValidationError:
    """A 422 naming the field at ``loc`` (e.g. ``("query", "from")``), as pydantic's are."""
    return RequestValidationError([{"loc": loc, "msg": message, "type": "value_error"}])


def _validation_answer(errors: Sequence[dict[str, Any]]) -> JSONResponse:
    entries = [
        {"loc": _location(tuple(e["loc"])), "msg": str(e["msg"]), "type": str(e["type"])}
        for e in errors
    ]
    shown = "; ".join(f"{e['loc']}: {e['msg']}" for e in entries[:DETAIL_FIELDS])
    more = f" (and {len(entries) - DETAIL_FIELDS} more)" if len(entries) > DETAIL_FIELDS else ""
    return JSONResponse(
        {"detail": f"invalid request: {shown}{more}", "errors": entries},
        status_code=status.HTTP_422_UNPROCESSABLE_CONTENT,
    )


#: The routes that answer a page when asked for HTML (:func:`answers_pages`): each
#: endpoint with its page's title and its default ``format``.
_PAGE_ROUTES: dict[Callable[..., Any], tuple[str, str, bool]] = {}
#: The report form's fields, shown again on the page of a refused request.
FORM_FIELDS = ("from", "to", "station", "operator", "lot", "part_number", "list")

Endpoint = TypeVar("Endpoint", bound=Callable[..., Any])


def answers_pages(
    title: str, default_format: str, *, form: bool = True
) -> Callable[[Endpoint], Endpoint]:
    """Mark a route whose ``format`` query parameter (``default_format`` when absent) may
    ask for an HTML page: a request it refuses as HTML is answered with a page (422, one
    line saying why, and with ``form`` the report's form to correct it), not with JSON.
    Put below ``@router.get``."""

    def mark(endpoint: Endpoint) -> Endpoint:
        _PAGE_ROUTES[endpoint] = (title, default_format, form)
        return endpoint

    return mark


def _page(request: Request) -> tuple[str, bool] | None:
    """The title of the page the request asked for and whether it shows the report's
    form; ``None`` when it asked for data."""
    found = _PAGE_ROUTES.get(request.scope.get("endpoint"))  # type: ignore[arg-type]
    if found is None:
        return None
    title, default, form = found
    return (title, form) if request.query_params.get("format", default) == "html" else None


def one_line(errors: Sequence[dict[str, Any]]) -> str:
    """What was refused, as a page says it: each field's problem, once."""
    parts = []
    for e in errors[:DETAIL_FIELDS]:
        name, message = str(tuple(e["loc"])[-1]), str(e["msg"])
        parts.append(message if message.startswith(name) else f"{name}: {message}")
    more = f" (and {len(errors) - DETAIL_FIELDS} more)" if len(errors) > DETAIL_FIELDS else ""
    return "; ".join(parts) + more


async def _validation_error(request: Request, exc: Exception) -> Response:
    assert isinstance(exc, RequestValidationError)
    page = _page(request)
    if page is not None:
        from api.language import request_language
        from station.report import html

        title, with_form = page
        form = {name: request.query_params.get(name, "") for name in FORM_FIELDS}
        problem = html.problem_page(
            title,
            one_line(exc.errors()),
            form if with_form else None,
            request_language(request),
        )
        return HTMLResponse(problem, status_code=status.HTTP_422_UNPROCESSABLE_CONTENT)
    return _validation_answer(exc.errors())


async def _calibration_mismatch(_request: Request, exc: Exception) -> JSONResponse:
    loc = ("body", "coefficients")
    return _validation_answer([{"loc": loc, "msg": str(exc), "type": "calibration_mismatch"}])


Handler = Callable[[Request, Exception], Awaitable[Response]]


def _answer(status_code: int) -> Handler:
    async def handler(_request: Request, exc: Exception) -> JSONResponse:
        return JSONResponse({"detail": str(exc)}, status_code=status_code)

    return handler


#: Seconds a client is asked to wait before it asks again, when reads are overloaded.
RETRY_AFTER_S = 10


def _retry_later(detail: str) -> JSONResponse:
    return JSONResponse(
        {"detail": detail},
        status_code=status.HTTP_503_SERVICE_UNAVAILABLE,
        headers={"Retry-After": str(RETRY_AFTER_S)},
    )


async def _reports_busy(_request: Request, exc: Exception) -> JSONResponse:
    log.warning("report refused: %s", exc)
    return _retry_later(str(exc))


async def _read_timeout(request: Request, _exc: Exception) -> JSONResponse:
    log.warning("%s %s: read timeout", request.method, request.url.path)
    return _retry_later(
        "the read took longer than the server's read timeout (CALSTATION_READ_TIMEOUT_S): "
        "retry later; for a report, a shorter range is quicker"
    )


async def _database_error(request: Request, exc: Exception) -> JSONResponse:
    """A read that ran out of time (the read timeout) apart from a database that is down."""
    if isinstance(exc, OperationalError) and is_statement_timeout(exc):
        return await _read_timeout(request, exc)
    return await _database_unavailable(request, exc)


async def _database_unavailable(_request: Request, exc: Exception) -> JSONResponse:
    log.error("results database unavailable: %s", (str(exc).splitlines() or [repr(exc)])[0])
    return JSONResponse(
        {"detail": "results database unavailable"},
        status_code=status.HTTP_503_SERVICE_UNAVAILABLE,
    )


def install_error_handlers(app: FastAPI) -> None:
    """Map the product's errors to their HTTP answers."""
    app.add_exception_handler(RequestValidationError, _validation_error)
    app.add_exception_handler(InputError, _answer(status.HTTP_400_BAD_REQUEST))
    app.add_exception_handler(RunConflictError, _answer(status.HTTP_409_CONFLICT))
    app.add_exception_handler(ReviewRefusedError, _answer(status.HTTP_409_CONFLICT))
    app.add_exception_handler(CalibrationMismatchError, _calibration_mismatch)
    app.add_exception_handler(SchemaOutOfDateError, _database_unavailable)
    app.add_exception_handler(OperationalError, _database_error)
    app.add_exception_handler(ReportsBusyError, _reports_busy)
    app.add_exception_handler(ReadTimeoutError, _read_timeout)
    app.add_exception_handler(DatabaseUnavailableError, _database_unavailable)
