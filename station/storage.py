"""Where the station puts its run records: the database directly, or the results server.

Both stores are idempotent on the run UUID, so an outbox may resend a record as often as
it likes: the first delivery stores it, every later one gets the stored run back.
Errors tell the outbox what to do::

    CalstationError
    └── StoreError
        ├── StoreUnavailableError   database or server unreachable, 5xx: keep, retry later
        └── SubmissionRefusedError  the record itself is refused (4xx): retrying will not help
"""

from typing import Protocol

import httpx
from sqlalchemy.exc import OperationalError

from db import (
    Database,
    DatabaseUnavailableError,
    RunConflictError,
    RunRepository,
    SubmitOutcome,
    open_database,
)
from station.closing import Closing
from station.errors import CalstationError
from station.records import RunRecord, StoredRun

__all__ = [
    "DatabaseStore",
    "HttpStore",
    "RunStore",
    "StoreError",
    "StoreUnavailableError",
    "SubmissionRefusedError",
    "SubmitOutcome",
]

RUNS_PATH = "/api/v1/runs"


class StoreError(CalstationError):
    """A run record could not be stored."""


class StoreUnavailableError(StoreError):
    """The store did not answer or failed on its side; the record may be sent again later."""


class SubmissionRefusedError(StoreError):
    """The store refused the record itself; sending it again will not help."""


class RunStore(Protocol):
    """Somewhere run records go: ``submit`` is idempotent on ``record.run_id``."""

    def submit(self, record: RunRecord) -> SubmitOutcome:
        """Store ``record`` (or find it stored already) and return the stored run."""
        ...

    def close(self) -> None:
        """Release connections."""
        ...


class DatabaseStore(Closing):
    """Store runs straight into the results database (default: the embedded SQLite file)."""

    def __init__(self, url: str | None = None, *, database: Database | None = None) -> None:
        try:
            self.database = database or open_database(url)
        except DatabaseUnavailableError as exc:
            raise StoreUnavailableError(str(exc)) from None

    def submit(self, record: RunRecord) -> SubmitOutcome:
        try:
            with self.database.session() as session, session.begin():
                return RunRepository(session).submit(record)
        except RunConflictError as exc:
            raise SubmissionRefusedError(str(exc)) from None
        except OperationalError as exc:
            url = self.database.engine.url
            raise StoreUnavailableError(str(DatabaseUnavailableError.of(url, exc))) from None

    def close(self) -> None:
        self.database.dispose()


class HttpStore(Closing):
    """Submit runs to the results server's ``POST /api/v1/runs`` with a station API key."""

    def __init__(
        self,
        server_url: str,
        api_key: str,
        *,
        timeout: float = 10.0,
        transport: httpx.BaseTransport | None = None,
    ) -> None:
        self.client = httpx.Client(
            base_url=server_url,
            headers={"Authorization": f"Bearer {api_key}"},
            timeout=timeout,
            transport=transport,
        )

    def submit(self, record: RunRecord) -> SubmitOutcome:
        try:
            response = self.client.post(RUNS_PATH, json=record.model_dump(mode="json"))
        except httpx.HTTPError as exc:
            raise StoreUnavailableError(
                f"results server {self.client.base_url} unreachable: {exc}"
            ) from None
        if response.status_code in (200, 201):
            return SubmitOutcome(
                created=response.status_code == 201,
                run=StoredRun.model_validate_json(response.content),
            )
        message = _detail(response)
        if response.is_client_error and response.status_code not in (408, 429):
            raise SubmissionRefusedError(
                f"results server refused run {record.run_id} ({response.status_code}): {message}"
            )
        raise StoreUnavailableError(f"results server answered {response.status_code}: {message}")

    def close(self) -> None:
        self.client.close()


def _detail(response: httpx.Response) -> str:
    try:
        detail = response.json().get("detail")
    except (ValueError, AttributeError):
        detail = None
    return str(detail) if detail else response.text[:200]
