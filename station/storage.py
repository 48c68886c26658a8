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
from pydantic import BaseModel
from sqlalchemy.exc import OperationalError, SQLAlchemyError

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
from station.records import RunRecord, RunSummary, StoredRun

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
UNITS_PATH = "/api/v1/units"


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

    def history(self, serial: str) -> list[RunSummary]:
        """Every stored run of the unit, oldest first; :class:`StoreUnavailableError`."""
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

    def history(self, serial: str) -> list[RunSummary]:
        try:
            with self.database.session() as session:
                return RunRepository(session).history(serial)
        except SQLAlchemyError as exc:
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

    def history(self, serial: str) -> list[RunSummary]:
        """``GET /api/v1/units/{serial}/runs``; a unit the server does not know has none."""
        try:
            response = self.client.get(f"{UNITS_PATH}/{serial}/runs")
            if response.status_code == 404:
                return []
            response.raise_for_status()
            return RunHistory.model_validate_json(response.content).data
        except (httpx.HTTPError, ValueError) as exc:
            raise StoreUnavailableError(
                f"results server {self.client.base_url}: no history of {serial}: {exc}"
            ) from None

    def close(self) -> None:
        self.client.close()


class RunHistory(BaseModel):
    """The body of ``GET /api/v1/units/{serial}/runs``."""

    data: list[RunSummary]


def _detail(response: httpx.Response) -> str:
    try:
        detail = response.json().get("detail")
    except (ValueError, AttributeError):
        detail = None
    return str(detail) if detail else response.text[:200]
