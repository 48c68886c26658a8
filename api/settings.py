"""Settings of the results server, read from ``CALSTATION_*`` environment variables."""

from pathlib import Path
from typing import Annotated, Any

from pydantic import AfterValidator, Field
from sqlalchemy import make_url

from db.report import PAGE
from db.settings import DatabaseSettings, DatabaseUrl
from station.domain.errors import InputError
from station.domain.product.laboratory import Laboratory, load_laboratory
from station.domain.quality.alerts import AlertRules, parse_alert_rules
from station.domain.quality.shifts import parse_shifts, shift_name
from station.report.period import plant_zone


def _shifts(text: str) -> str:
    try:
        return ",".join(shift_name(at) for at in parse_shifts(text))
    except InputError as exc:
        raise ValueError(str(exc)) from None


def _alert_rules(path: Path | None) -> Path | None:
    """The rules file, if it can be read and holds rules (checked at start-up)."""
    if path is not None:
        try:
            parse_alert_rules(path.read_text("utf-8"), str(path))
        except OSError as exc:
            raise ValueError(f"{path}: {exc.strerror}") from None
        except (InputError, UnicodeDecodeError) as exc:
            raise ValueError(str(exc)) from None
    return path


def _laboratory_file(path: Path | None) -> Path | None:
    """The laboratory's file, if it can be read and holds a ``[laboratory]`` table."""
    if path is not None:
        try:
            load_laboratory(path)
        except InputError as exc:
            raise ValueError(str(exc)) from None
    return path


def _zone(name: str) -> str:
    try:
        return plant_zone(name)
    except InputError as exc:
        raise ValueError(str(exc)) from None


class ApiSettings(DatabaseSettings):
    """Database location plus the server's own switches.

    ``read_requires_key``: read endpoints need an API key too (default: open on
    the plant network). ``max_body_bytes``: larger request bodies are refused with 413.
    ``read_pool_size`` and ``write_pool_size``: database connections of each server
    process for reads and for submissions. ``report_pool_size``: connections (and
    threads) of each server process for the end-of-line report and the dashboard, apart
    from the others so that readers never take the stations' connections.
    ``read_timeout_s``: longest statement of a read (PostgreSQL ``statement_timeout``;
    on SQLite the report's statements only); ``report_wait_s``: longest wait for a free
    report connection. Either exceeded answers 503. ``plant_timezone``
    (``CALSTATION_PLANT_TIMEZONE``, an IANA name): the zone the report and dashboard show
    times and days in, and read dates without a zone in; stored times stay UTC.
    ``plant_shifts`` (``CALSTATION_PLANT_SHIFTS``, e.g. ``06:00,14:00,22:00``): the
    shifts' start times in that zone; the report adds a trend per shift.
    ``event_listeners`` (``CALSTATION_EVENT_LISTENERS``): the most event streams
    (``GET /api/v1/events``) each server process serves at once; one more is answered
    503 with ``Retry-After`` (:mod:`api.routes.events`). ``alerts_file``
    (``CALSTATION_ALERTS_FILE``): the plant's alert rules and webhook (TOML,
    :mod:`station.domain.quality.alerts`), checked every ``alert_interval_s``; a post the
    webhook refused is tried again after ``alert_retry_s`` (:mod:`api.alerts`).
    ``export_page_size`` (``CALSTATION_EXPORT_PAGE_SIZE``): runs per page of the CSV
    export (``GET /api/v1/reports/eol/runs.csv``), each page one statement under
    ``read_timeout_s`` and held in memory while it is written: a slow or distant
    database wants smaller pages (each read well inside the time-out, the answer's
    first page sooner), a fast one larger (fewer round trips). ``laboratory_file``
    (``CALSTATION_LABORATORY_FILE``): a TOML file whose ``[laboratory]`` table names the
    laboratory, its address, where it calibrates, the customer and the traceability of
    its reference, as its certificates state them (:mod:`station.domain.product.laboratory`).
    ``report_database_url`` (``CALSTATION_REPORT_DATABASE_URL``): a streaming replica of
    the database (PostgreSQL hot standby) that the report processes read: the end-of-line
    report, the dashboard, the split, the failing runs and the station pages
    (:mod:`api.report_pool`). Submissions, reviews, keys, what-if profiles, alerts' state,
    the unit's own pages and the CSV export stay on the primary. A replica holds the
    primary's roles, so ``database_password`` is its password too. Unset: the report reads
    the primary (docs/api.md, "Scaling out").
    ``prepared_statements`` (``CALSTATION_PREPARED_STATEMENTS``): psycopg prepares a
    statement on a connection once it ran five times there. Behind a pooler in
    transaction mode that does not carry prepared statements across its server
    connections (pgbouncer before 1.21), the next transaction finds it missing
    (``prepared statement "_pg3_0" does not exist``): ``false`` turns preparing off.
    """

    read_requires_key: bool = False
    max_body_bytes: Annotated[int, Field(ge=1024)] = 1024 * 1024
    read_pool_size: Annotated[int, Field(ge=1)] = 8
    write_pool_size: Annotated[int, Field(ge=1)] = 6
    report_pool_size: Annotated[int, Field(ge=1)] = 1
    read_timeout_s: Annotated[float, Field(gt=0, le=3600)] = 30.0
    report_wait_s: Annotated[float, Field(gt=0, le=3600)] = 10.0
    plant_timezone: Annotated[str, AfterValidator(_zone)] = "UTC"
    plant_shifts: Annotated[str, AfterValidator(_shifts)] = ""
    event_listeners: Annotated[int, Field(ge=1)] = 64
    alerts_file: Annotated[Path | None, AfterValidator(_alert_rules)] = None
    alert_interval_s: Annotated[float, Field(gt=0, le=3600)] = 60.0
    alert_retry_s: Annotated[float, Field(gt=0, le=3600)] = 60.0
    export_page_size: Annotated[int, Field(ge=1)] = PAGE
    laboratory_file: Annotated[Path | None, AfterValidator(_laboratory_file)] = None
    report_database_url: DatabaseUrl | None = None
    prepared_statements: bool = True

    def laboratory(self) -> Laboratory:
        """The laboratory its certificates name (``laboratory_file``; none: unnamed)."""
        if self.laboratory_file is None:
            return Laboratory()
        return load_laboratory(self.laboratory_file)

    def engine_options(self) -> dict[str, Any]:
        """Keywords of every engine of the server: no prepared statements when they are
        off (PostgreSQL's driver; SQLite prepares nothing across transactions)."""
        if self.prepared_statements or make_url(self.url()).get_backend_name() != "postgresql":
            return {}
        return {"connect_args": {"prepare_threshold": None}}

    def report_url(self) -> str:
        """The URL the report processes connect to: the replica's, else :meth:`url`."""
        if self.report_database_url is None:
            return self.url()
        if self.database_password is None:
            return self.report_database_url
        url = make_url(self.report_database_url)
        return url.set(password=self.database_password.get_secret_value()).render_as_string(
            hide_password=False
        )

    def alert_rules(self) -> AlertRules | None:
        """The plant's alert rules (``alerts_file``), if it has any."""
        if self.alerts_file is None:
            return None
        return parse_alert_rules(self.alerts_file.read_text("utf-8"), str(self.alerts_file))
