"""The report from a streaming replica: which reads go to ``CALSTATION_REPORT_DATABASE_URL``.

Two real PostgreSQL databases of the test server: the primary and a second database
standing in for the replica. What is tested is the server's wiring (which connection
each request takes); the replication itself is PostgreSQL's own. A run stored in only
one of the two shows where each read went.
"""

from collections.abc import Iterator
from datetime import UTC, datetime, timedelta

import pytest
from pydantic import SecretStr
from sqlalchemy import make_url, select

from api.settings import ApiSettings
from db import Database, RunRepository, open_database
from db.models import Run
from tests.databases import own_postgres_database
from tests.db.records import make_record
from tests.servers import local_client, serving

PRIMARY_STATION, REPLICA_STATION = "line1-st1", "line9-st9"
PRIMARY_SERIAL, REPLICA_SERIALS = "PT-PRIMARY", ["PT-REPLICA1", "PT-REPLICA2"]


@pytest.fixture
def primary_and_replica() -> Iterator[tuple[Database, Database]]:
    """Two migrated PostgreSQL databases of their own, dropped after the test."""
    with (
        own_postgres_database("calstation_primary") as primary_url,
        own_postgres_database("calstation_replica") as replica_url,
    ):
        primary = open_database(primary_url, auto_migrate=True)
        replica = open_database(replica_url, auto_migrate=True)
        try:
            yield primary, replica
        finally:
            primary.dispose()
            replica.dispose()


def _serials(database: Database) -> list[str]:
    with database.session() as session:
        return list(session.scalars(select(Run.serial).order_by(Run.serial)))


@pytest.mark.postgres
def test_the_report_reads_the_replica_and_everything_else_the_primary(
    primary_and_replica: tuple[Database, Database],
) -> None:
    primary, replica = primary_and_replica
    now = datetime.now(UTC)  # the dashboard shows the plant's (UTC's) today
    today = max(now - timedelta(minutes=10), now.replace(hour=0, minute=0, second=0))
    with primary.session() as session, session.begin():
        key = RunRepository(session).create_key(PRIMARY_STATION)
    with replica.session() as session, session.begin():
        for serial in REPLICA_SERIALS:  # two runs there, one in the primary
            RunRepository(session).submit(
                make_record(serial=serial, station_id=REPLICA_STATION, started_at=today)
            )
    stored = make_record(serial=PRIMARY_SERIAL, station_id=PRIMARY_STATION, started_at=today)
    primary_url = primary.engine.url.render_as_string(hide_password=False)
    replica_url = replica.engine.url.render_as_string(hide_password=False)

    with (
        serving(primary_url, report_database_url=replica_url) as base,
        local_client(base) as client,
    ):
        answer = client.post(
            "/api/v1/runs",
            json=stored.model_dump(mode="json"),
            headers={"Authorization": f"Bearer {key}"},
        )
        assert answer.status_code == 201, answer.text
        # The submission and the key: the primary's.
        assert _serials(primary) == [PRIMARY_SERIAL]
        assert _serials(replica) == [*REPLICA_SERIALS]
        # The unit's own answers read the primary: the run just stored is there.
        assert client.get(f"/api/v1/units/{PRIMARY_SERIAL}").status_code == 200
        assert client.get(f"/api/v1/units/{REPLICA_SERIALS[0]}").status_code == 404
        assert client.get(f"/api/v1/units/{PRIMARY_SERIAL}/certificate").status_code == 200
        # The report, the dashboard and the station pages read the replica.
        report = client.get("/api/v1/reports/eol", params={"format": "json"}).json()
        assert report["summary"]["runs"] == len(REPLICA_SERIALS)
        assert REPLICA_SERIALS[0] in client.get("/").text
        assert client.get(f"/stations/{REPLICA_STATION}").status_code == 200
        assert client.get(f"/stations/{PRIMARY_STATION}").status_code == 404
        split = client.get(
            "/api/v1/reports/split",
            params={"parameter": "offset_x", "by": "station", "format": "json"},
        ).json()
        assert split["sampled_runs"] == len(REPLICA_SERIALS)


@pytest.mark.postgres
def test_an_unreachable_replica_is_a_503_of_the_report_and_nothing_else(
    primary_and_replica: tuple[Database, Database],
) -> None:
    primary, _ = primary_and_replica
    primary_url = primary.engine.url.render_as_string(hide_password=False)
    missing = primary.engine.url.set(database="calstation_no_such_replica")
    replica_url = missing.render_as_string(hide_password=False)
    with serving(primary_url, report_database_url=replica_url) as base, local_client(base) as c:
        report = c.get("/api/v1/reports/eol", params={"format": "json"})
        assert report.status_code == 503
        assert report.json()["detail"] == "results database unavailable"
        assert c.get("/api/v1/units/PT-NONE").status_code == 404  # the primary answers
        assert c.get("/healthz").status_code == 200


def test_the_replica_takes_the_primarys_password_and_unset_is_the_primary() -> None:
    settings = ApiSettings(
        database_url="postgresql+psycopg://calstation@primary/calstation",
        report_database_url="postgresql+psycopg://calstation@replica/calstation",
        database_password=SecretStr("p@ss:w/rd"),
    )
    replica = make_url(settings.report_url())
    assert (replica.host, replica.password) == ("replica", "p@ss:w/rd")
    alone = ApiSettings(database_url="postgresql+psycopg://calstation@primary/calstation")
    assert alone.report_url() == alone.url()
