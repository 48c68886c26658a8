"""JSON answers serialised once, by pydantic, without FastAPI validating them again."""

from fastapi import Response, status
from pydantic import BaseModel


def json_response(model: BaseModel, status_code: int = status.HTTP_200_OK) -> Response:
    """``model`` as a JSON response (the route declares ``response_model`` for OpenAPI)."""
    return Response(model.model_dump_json(), status_code=status_code, media_type="application/json")
