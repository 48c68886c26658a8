"""Where the station puts its run records: the database directly, or the results server.

Both stores are idempotent on the run UUID, so an outbox may resend a record as often as
it likes: the first delivery stores it, every later one gets the stored run back.
This module is the station loop's one door to storage: nothing else in the loop imports
:mod:`db`, :mod:`api` or SQLAlchemy (an import-linter contract keeps it so), and the
settings that say where the database is (:data:`DatabaseUrl`, :data:`DataDir`) come
through here too. Every failure of a store, whatever the database driver or HTTP client
raised, leaves this module as one of these errors, which tell the outbox what to do::

    CalstationError
    └── StoreError
        ├── StoreUnavailableError       unreachable (connection, timeout, 502/503/504,
        │   │                           408/429): every record waits, retry later
        │   └── StoreConfigurationError the station's key or URL is wrong (401/403, 404/405,
        │                               other 4xx): every record waits until it is fixed
        ├── RecordFailedError           the store answered but failed on this record (500,
        │                               a database error other than a lost connection):
        │                               retry this one with backoff, send the others
        └── SubmissionRefusedError      the record itself is invalid (400, 409, 413, 422):
                                        retrying will not help
"""

from typing import Protocol

import httpx
from pydantic import BaseModel, ValidationError
from sqlalchemy.exc import (
    ArgumentError,
    DBAPIError,
    InterfaceError,
    OperationalError,
    SQLAlchemyError,
)

from db import (
    Database,
    DatabaseUnavailableError,
    RunConflictError,
    RunRepository,
    SchemaOutOfDateError,
    SubmitOutcome,
    open_database,
)
from db.settings import DatabaseUrl, DataDir, default_data_dir
from station.domain.closing import Closing
from station.domain.errors import CalstationError, InputError
from station.domain.record.outbox_report import OUTBOX_HEADER, OutboxReport
from station.domain.record.records import (
    GyroFitRecord,
    HoldReview,
    RunRecord,
    RunSummary,
    StoredRun,
)

__all__ = [
    "DataDir",
    "DatabaseStore",
    "DatabaseUrl",
    "HttpStore",
    "RecordFailedError",
    "RunStore",
    "StoreConfigurationError",
    "StoreError",
    "StoreUnavailableError",
    "SubmissionRefusedError",
    "SubmitOutcome",
    "default_data_dir",
]

RUNS_PATH = "/api/v1/runs"
UNITS_PATH = "/api/v1/units"
#: Seconds the scan waits for a unit's history from the results server: the operator
#: stands at the station, and without an answer the unit is calibrated all the same.
HISTORY_TIMEOUT_S = 2.0


class StoreError(CalstationError):
    """A run record could not be stored."""


class StoreUnavailableError(StoreError):
    """The store did not answer or failed on its side; the record may be sent again later."""


class StoreConfigurationError(StoreUnavailableError):
    """The store refused this station (key, URL): no record goes until the setting is fixed."""


class RecordFailedError(StoreError):
    """The store answered but failed on this record: retry it later, send the others now."""


class SubmissionRefusedError(StoreError):
    """The store refused the record itself; sending it again will not help."""


class RunStore(Protocol):
    """Somewhere run records go: ``submit`` is idempotent on ``record.run_id``.

    Opening a store and every method raise only :class:`StoreError` (and its kinds).
    """

    def submit(self, record: RunRecord, outbox: OutboxReport | None = None) -> SubmitOutcome:
        """Store ``record`` (or find it stored already) and return the stored run;
        ``outbox``: the station's outbox as it sends it, kept as its latest report."""
        ...

    def history(self, serial: str) -> list[RunSummary]:
        """Every stored run of the unit, oldest first; :class:`StoreUnavailableError`."""
        ...

    def gyro_fit(self, serial: str) -> GyroFitRecord | None:
        """The unit's latest [Park2014]_ gyro fit, or None; :class:`StoreUnavailableError`."""
        ...

    def reviews(self, serial: str) -> list[HoldReview]:
        """The unit's quality reviews, oldest first; :class:`StoreUnavailableError`."""
        ...

    def close(self) -> None:
        """Release connections."""
        ...


class DatabaseStore(Closing):
    """Store runs straight into the results database (default: the embedded SQLite file)."""

    def __init__(self, url: str | None = None, *, database: Database | None = None) -> None:
        try:
            self.database = database or open_database(url)
        except (DatabaseUnavailableError, OSError) as exc:
            raise StoreUnavailableError(str(exc)) from None
        except (SchemaOutOfDateError, InputError) as exc:
            raise StoreConfigurationError(str(exc)) from None
        except ArgumentError as exc:
            raise StoreConfigurationError(f"database URL: {_first_line(exc)}") from None
        except SQLAlchemyError as exc:
            raise StoreUnavailableError(f"database: {_first_line(exc)}") from None

    def submit(self, record: RunRecord, outbox: OutboxReport | None = None) -> SubmitOutcome:
        try:
            with self.database.session() as session, session.begin():
                return RunRepository(session).submit(record, outbox=outbox)
        except RunConflictError as exc:
            raise SubmissionRefusedError(str(exc)) from None
        except SQLAlchemyError as exc:
            url = self.database.engine.url
            if _connection_lost(exc):
                raise StoreUnavailableError(str(DatabaseUnavailableError.of(url, exc))) from None
            raise RecordFailedError(
                f"database failed on run {record.run_id}: {_first_line(exc)}"
            ) from None

    def history(self, serial: str) -> list[RunSummary]:
        try:
            with self.database.session() as session:
                return RunRepository(session).history(serial)
        except SQLAlchemyError as exc:
            url = self.database.engine.url
            raise StoreUnavailableError(str(DatabaseUnavailableError.of(url, exc))) from None

    def gyro_fit(self, serial: str) -> GyroFitRecord | None:
        try:
            with self.database.session() as session:
                return RunRepository(session).latest_gyro_fit(serial)
        except SQLAlchemyError as exc:
            url = self.database.engine.url
            raise StoreUnavailableError(str(DatabaseUnavailableError.of(url, exc))) from None

    def reviews(self, serial: str) -> list[HoldReview]:
        try:
            with self.database.session() as session:
                return RunRepository(session).reviews(serial)
        except SQLAlchemyError as exc:
            url = self.database.engine.url
            raise StoreUnavailableError(str(DatabaseUnavailableError.of(url, exc))) from None

    def close(self) -> None:
        self.database.dispose()


class HttpStore(Closing):
    """Submit runs to the results server's ``POST /api/v1/runs`` with a station API key.

    ``station_id``: the station the key belongs to. A run recorded under another id (the
    station renamed with runs still queued) is refused here, unsent: the server would
    answer 403, which reads as a bad key and would hold up every run behind it.
    """

    def __init__(
        self,
        server_url: str,
        api_key: str,
        *,
        station_id: str | None = None,
        timeout: float = 10.0,
        transport: httpx.BaseTransport | None = None,
    ) -> None:
        self.station_id = station_id
        self.client = httpx.Client(
            base_url=server_url,
            headers={"Authorization": f"Bearer {api_key}"},
            timeout=timeout,
            transport=transport,
        )

    def submit(self, record: RunRecord, outbox: OutboxReport | None = None) -> SubmitOutcome:
        """POST the run, the outbox's report in the ``Calstation-Outbox`` header."""
        if self.station_id is not None and record.station_id != self.station_id:
            raise SubmissionRefusedError(
                f"run {record.run_id} was recorded by station {record.station_id}, and this "
                f"station sends as {self.station_id}: only a key of {record.station_id} can "
                f"store it (calstation outbox send {record.run_id} --api-key KEY)"
            )
        try:
            headers = {} if outbox is None else {OUTBOX_HEADER: outbox.header()}
            response = self._post(record.model_dump(mode="json"), headers)
        except httpx.HTTPError as exc:
            raise StoreUnavailableError(
                f"results server {self.client.base_url} unreachable: {exc}"
            ) from None
        if response.status_code in (200, 201):
            try:
                run = StoredRun.model_validate_json(response.content)
            except ValidationError:
                raise RecordFailedError(
                    f"results server answered run {record.run_id} with no stored run"
                ) from None
            return SubmitOutcome(created=response.status_code == 201, run=run)
        raise _http_error(self.client.base_url, record, response)

    def _post(self, body: dict[str, object], headers: dict[str, str]) -> httpx.Response:
        """POST the run; once more on a fresh connection if a kept-alive one was dropped.

        The server closes its connection after a 500, so the next record's request may
        meet a closed socket: that says nothing about the server being reachable, and
        the submission is idempotent, so it is simply sent again.
        """
        try:
            return self.client.post(RUNS_PATH, json=body, headers=headers)
        except (httpx.ReadError, httpx.WriteError, httpx.RemoteProtocolError):
            return self.client.post(RUNS_PATH, json=body, headers=headers)

    def history(self, serial: str) -> list[RunSummary]:
        """``GET /api/v1/units/{serial}/runs``; a unit the server does not know has none."""
        try:
            response = self.client.get(f"{UNITS_PATH}/{serial}/runs", timeout=HISTORY_TIMEOUT_S)
            if response.status_code == 404:
                return []
            response.raise_for_status()
            return RunHistory.model_validate_json(response.content).data
        except (httpx.HTTPError, ValueError) as exc:
            raise StoreUnavailableError(
                f"results server {self.client.base_url}: no history of {serial}: {exc}"
            ) from None

    def gyro_fit(self, serial: str) -> GyroFitRecord | None:
        """``GET /api/v1/units/{serial}/gyro``'s ``fit``; a unit the server does not know
        has none."""
        try:
            response = self.client.get(f"{UNITS_PATH}/{serial}/gyro", timeout=HISTORY_TIMEOUT_S)
            if response.status_code == 404:
                return None
            response.raise_for_status()
            return UnitGyroFit.model_validate_json(response.content).fit
        except (httpx.HTTPError, ValueError) as exc:
            raise StoreUnavailableError(
                f"results server {self.client.base_url}: no gyro fit of {serial}: {exc}"
            ) from None

    def reviews(self, serial: str) -> list[HoldReview]:
        """``GET /api/v1/units/{serial}/reviews``."""
        try:
            response = self.client.get(f"{UNITS_PATH}/{serial}/reviews", timeout=HISTORY_TIMEOUT_S)
            response.raise_for_status()
            return UnitReviews.model_validate_json(response.content).data
        except (httpx.HTTPError, ValueError) as exc:
            raise StoreUnavailableError(
                f"results server {self.client.base_url}: no reviews of {serial}: {exc}"
            ) from None

    def close(self) -> None:
        self.client.close()


def _first_line(exc: SQLAlchemyError) -> str:
    """The driver's own first line (SQLAlchemy's message adds the whole statement)."""
    driver = getattr(exc, "orig", None) or exc
    return (str(driver).strip().splitlines() or [type(driver).__name__])[0]


def _connection_lost(exc: SQLAlchemyError) -> bool:
    """Whether ``exc`` says the database is out of reach, not that this record failed.

    Operational and interface errors are the driver's "no connection, timeout, server
    shutting down, database locked or full"; any other error (a numeric overflow, a
    constraint) came back from a working database about this record's statements.
    """
    if isinstance(exc, DBAPIError) and exc.connection_invalidated:
        return True
    return isinstance(exc, OperationalError | InterfaceError)


#: Answers that say the record itself is invalid: it goes to ``refused/``.
REFUSED = frozenset({400, 409, 413, 422})
#: Answers that say the server cannot take anything now: every record waits.
BUSY = frozenset({408, 425, 429, 502, 503, 504})
#: Answers that say this station's key is not accepted.
KEY_REFUSED = frozenset({401, 403, 407})
#: Answers that say there is no run endpoint at this URL.
WRONG_URL = frozenset({404, 405, 410})


def _http_error(base_url: httpx.URL, record: RunRecord, response: httpx.Response) -> StoreError:
    """The outbox's error for a non-2xx answer to the submission of ``record``."""
    code, message = response.status_code, _detail(response)
    if code in REFUSED:
        return SubmissionRefusedError(
            f"results server refused run {record.run_id} ({code}): {message}"
        )
    if code in BUSY:
        return StoreUnavailableError(f"results server answered {code}: {message}")
    if code in KEY_REFUSED:
        return StoreConfigurationError(
            f"results server refused this station's API key ({code}: {message}): fix api_key"
        )
    if code in WRONG_URL:
        return StoreConfigurationError(
            f"results server {base_url} has no run endpoint ({code}): fix server_url"
        )
    if response.is_server_error:
        return RecordFailedError(
            f"results server failed on run {record.run_id} ({code}): {message}"
        )
    return StoreConfigurationError(
        f"results server answered {code} ({message}): check server_url and api_key"
    )


class UnitGyroFit(BaseModel):
    """The part of ``GET /api/v1/units/{serial}/gyro`` the station reads."""

    fit: GyroFitRecord | None


class RunHistory(BaseModel):
    """The body of ``GET /api/v1/units/{serial}/runs``."""

    data: list[RunSummary]


class UnitReviews(BaseModel):
    """The part of ``GET /api/v1/units/{serial}/reviews`` the station reads."""

    data: list[HoldReview]


def _detail(response: httpx.Response) -> str:
    try:
        detail = response.json().get("detail")
    except (ValueError, AttributeError):
        detail = None
    return str(detail) if detail else response.text[:200]
