"""A bounded schemathesis run: every documented operation of the real server, on SQLite
and PostgreSQL, with generated valid and invalid requests; no answer may be a 5xx, and
every answer must be documented (status, media type, body schema).

Bounded and repeatable: a fixed number of examples per operation (:data:`EXAMPLES` in
the nightly profile, fewer in ``make test``: ``tests.conftest.examples``), derandomized,
no example database; a few seconds per backend. The line's event stream
(``GET /api/v1/events``) never ends, so no call to it can be checked whole here: it takes
no input, and ``tests/api/test_unit_pages.py`` reads its answer (status, media type, a
pushed run's ``RunEvent``).
"""

from collections.abc import Callable
from typing import Any

import httpx
import pytest
import schemathesis
from hypothesis import HealthCheck, Phase, given, settings
from schemathesis import GenerationMode
from schemathesis.checks import not_a_server_error
from schemathesis.specs.openapi.checks import (
    content_type_conformance,
    response_schema_conformance,
    status_code_conformance,
)

from api.main import create_app
from api.settings import ApiSettings
from tests.conftest import examples
from tests.db.records import make_record
from tests.servers import STATION

#: The document the server serves, read without starting it (no database needed).
DOCUMENT: dict[str, Any] = create_app(ApiSettings()).openapi()
#: Each operation with valid requests, and with invalid ones where it takes any input;
#: event streams aside (an answer that never ends).
OPERATIONS = [
    (path, method, mode)
    for path, ops in DOCUMENT["paths"].items()
    for method, op in ops.items()
    for mode in (GenerationMode.POSITIVE, GenerationMode.NEGATIVE)
    if mode == GenerationMode.POSITIVE or op.get("parameters") or op.get("requestBody")
    if "text/event-stream" not in op["responses"].get("200", {}).get("content", {})
]
CHECKS = [
    not_a_server_error,
    status_code_conformance,
    content_type_conformance,
    response_schema_conformance,
]
#: Examples per operation and generation mode at night: enough to reach every
#: parameter's edges.
EXAMPLES = 25


def test_the_served_document_is_the_one_tested(client: httpx.Client) -> None:
    assert client.get("/openapi.json").json() == DOCUMENT


def _own_station(case: Any) -> None:
    """Submissions name the key's station, so they reach the solve and the database."""
    if case.method == "POST" and case.path == "/api/v1/runs" and isinstance(case.body, dict):
        case.body["station_id"] = STATION


@pytest.mark.parametrize(("path", "method", "mode"), OPERATIONS)
def test_no_5xx_and_every_answer_documented(
    client: httpx.Client, station_key: str, path: str, method: str, mode: GenerationMode
) -> None:
    stored = make_record()
    client.post(
        "/api/v1/runs",
        json=stored.model_dump(mode="json"),
        headers={"Authorization": f"Bearer {station_key}"},
    ).raise_for_status()
    operation = schemathesis.openapi.from_dict(DOCUMENT)[path][method.upper()]
    base_url = str(client.base_url)

    @settings(
        max_examples=examples(EXAMPLES),
        derandomize=True,
        database=None,
        deadline=None,
        phases=[Phase.explicit, Phase.generate],
        suppress_health_check=list(HealthCheck),
    )
    @given(case=operation.as_strategy(generation_mode=mode))
    def call(case: Any) -> None:
        _own_station(case)
        headers = {"Authorization": f"Bearer {station_key}"}
        response = case.call(base_url=base_url, headers=headers, timeout=30)
        case.validate_response(response, checks=CHECKS, headers=headers)

    run: Callable[[], None] = call
    run()
