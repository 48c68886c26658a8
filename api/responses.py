"""What the API answers: JSON bodies, and the one definition of every error answer.

:func:`problems` gives the ``responses=`` entries of the error answers a route (or a
router, or the whole app) can give, so the OpenAPI document lists each answer the
server actually gives, with the body it actually has (:mod:`api.errors`).
"""

from typing import Any

from fastapi import Response, status
from pydantic import BaseModel

from api.schemas import Problem, ValidationProblem

#: Why the server gives each error answer, as the OpenAPI document says it.
PROBLEMS: dict[int, str] = {
    400: "the body cannot be read (not UTF-8), or a cursor this server never gave",
    401: "no API key, or an unknown or revoked one",
    403: "the API key may not do this",
    404: "nothing stored under this name",
    409: "a run with this UUID is stored with different content",
    413: "the request body is larger than the server accepts",
    422: "a field, parameter or body is invalid (each offending one is named in errors)",
    503: "the results database does not answer, or is not at the current schema",
}


def problems(*codes: int, **descriptions: str) -> dict[int | str, dict[str, Any]]:
    """``responses=`` entries for the error answers ``codes``, JSON bodies.

    ``descriptions`` overrides a description per code (``_404="no run of this serial"``).
    """
    return {
        code: {
            "model": ValidationProblem
            if code == status.HTTP_422_UNPROCESSABLE_CONTENT
            else Problem,
            "description": descriptions.get(f"_{code}", PROBLEMS[code]),
        }
        for code in codes
    }


def json_problems(*codes: int, **descriptions: str) -> dict[int | str, dict[str, Any]]:
    """:func:`problems` for a route whose own answer is not JSON (an event stream): the
    error bodies stay JSON, so their media type is named here, not taken from the route.

    The schemas are referred to by name: :func:`problems` of the other routes define them.
    """
    return {
        code: {
            "description": entry["description"],
            "content": {
                "application/json": {
                    "schema": {"$ref": f"#/components/schemas/{entry['model'].__name__}"}
                }
            },
        }
        for code, entry in problems(*codes, **descriptions).items()
    }


def json_response(model: BaseModel, status_code: int = status.HTTP_200_OK) -> Response:
    """``model`` as a JSON response (the route declares ``response_model`` for OpenAPI)."""
    return Response(model.model_dump_json(), status_code=status_code, media_type="application/json")
