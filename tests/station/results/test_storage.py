"""The station's run stores: straight into the database, or over HTTP to a live server."""

import sqlite3
from contextlib import closing
from datetime import UTC, datetime
from pathlib import Path

import httpx
import pytest

from db import Database, RunRepository
from station.domain.gyro import fit_log, paper_truth, simulate_log
from station.domain.record.records import GyroFitRecord, RunRecord, Vector3
from station.results.storage import (
    DatabaseStore,
    HttpStore,
    RecordFailedError,
    StoreConfigurationError,
    StoreError,
    StoreUnavailableError,
    SubmissionRefusedError,
)
from tests.db.records import make_record
from tests.servers import free_port, local_get


def poison(record: RunRecord) -> RunRecord:
    """``record`` with a pose spread of 1e300: finite, but beyond any SQL numeric.

    Built without validation, so it stays poison whatever bounds the model has.
    """
    first = record.poses[0].model_copy(update={"std": Vector3(x=1e300, y=1.0, z=1.0)})
    return record.model_copy(update={"poses": (first, *record.poses[1:])})


def test_the_database_store_is_idempotent_on_the_run_uuid(database: Database) -> None:
    record = make_record()
    store = DatabaseStore(database=database)
    first, again = store.submit(record), store.submit(record)
    assert (first.created, again.created) == (True, False)
    assert again.run == first.run
    with database.session() as session:
        assert len(RunRepository(session).history(record.serial)) == 1


def test_the_database_store_refuses_a_clashing_uuid(database: Database) -> None:
    record = make_record()
    store = DatabaseStore(database=database)
    store.submit(record)
    with pytest.raises(SubmissionRefusedError, match="different content"):
        store.submit(record.model_copy(update={"operator_id": "op-2"}))


def test_the_http_store_submits_and_retries_against_a_live_server(
    live_url: str, database: Database, station_key: str
) -> None:
    record = make_record()
    with HttpStore(live_url, station_key) as store:
        first, again = store.submit(record), store.submit(record)
    assert (first.created, again.created) == (True, False)
    assert first.run.model_dump(exclude={"received_at"}) == record.model_dump()
    assert again.run == first.run
    unit = local_get(f"{live_url}/api/v1/units/{record.serial}").json()
    assert unit["latest"]["run_id"] == unit["holds"]["run_id"] == str(record.run_id)


def test_the_http_store_tells_a_refusal_from_an_outage(
    live_url: str, database: Database, station_key: str
) -> None:
    with (
        HttpStore(live_url, "csk_wrong") as store,
        pytest.raises(StoreConfigurationError, match=r"API key \(401.*fix api_key"),
    ):
        store.submit(make_record())
    with (
        HttpStore(f"{live_url}/not-here", station_key) as store,
        pytest.raises(StoreConfigurationError, match=r"\(404\): fix server_url"),
    ):
        store.submit(make_record())
    bad = make_record(offset=(2000.0, 2000.0, 2000.0))
    body = bad.model_dump(mode="json")
    body["coefficients"]["offset"]["x"] = 2100.0
    with (
        HttpStore(live_url, station_key) as store,
        pytest.raises(SubmissionRefusedError, match=r"422.*offset\[0\]"),
    ):
        store.submit(type(bad).model_validate(body))
    with (
        HttpStore(f"http://127.0.0.1:{free_port()}", station_key, timeout=2) as store,
        pytest.raises(StoreUnavailableError, match="unreachable"),
    ):
        store.submit(make_record())


def test_a_database_error_on_one_record_blames_the_record_not_the_store(
    database: Database,
) -> None:
    if database.is_sqlite:
        pytest.skip("SQLite stores 1e300 as it is: no error to tell apart")
    store = DatabaseStore(database=database)
    with pytest.raises(RecordFailedError, match="out of range"):
        store.submit(poison(make_record(serial="PT-POISON")))
    store.submit(make_record(serial="PT-GOOD"))  # the same store goes on


def test_a_database_that_does_not_answer_is_unavailable() -> None:
    url = f"postgresql+psycopg://postgres@127.0.0.1:{free_port()}/test?connect_timeout=2"
    with pytest.raises(StoreUnavailableError) as raised:
        DatabaseStore(url)
    assert not isinstance(raised.value, StoreConfigurationError)


def test_a_database_the_station_cannot_use_waits_for_its_setting_to_be_fixed(
    tmp_path: Path,
) -> None:
    with pytest.raises(StoreConfigurationError, match="nosuch"):
        DatabaseStore("nosuch://host/db")
    url = f"sqlite:///{tmp_path / 'newer.sqlite3'}"
    DatabaseStore(url).close()
    with closing(sqlite3.connect(tmp_path / "newer.sqlite3")) as connection, connection:
        connection.execute("UPDATE alembic_version SET version_num = 'ffffffffffff'")
    with pytest.raises(StoreConfigurationError, match="newer calstation"):
        DatabaseStore(url)


def test_a_success_answer_without_a_stored_run_blames_the_record() -> None:
    # A proxy answering 200 with its own page: nothing says the run is stored.
    transport = httpx.MockTransport(lambda _: httpx.Response(200, text="<html>welcome</html>"))
    record = make_record()
    with (
        HttpStore("http://results", "key", transport=transport) as store,
        pytest.raises(RecordFailedError, match=f"answered run {record.run_id} with no stored run"),
    ):
        store.submit(record)


# The real server never answers these (it answers 401, 404, 409, 422 above), so a mock
# transport plays a proxy, a broken server, or a future server refusing a key's scope.
@pytest.mark.parametrize(
    ("status", "error"),
    [
        (400, SubmissionRefusedError),
        (413, SubmissionRefusedError),
        (403, StoreConfigurationError),
        (405, StoreConfigurationError),
        (418, StoreConfigurationError),
        (302, StoreConfigurationError),
        (429, StoreUnavailableError),
        (502, StoreUnavailableError),
        (503, StoreUnavailableError),
        (504, StoreUnavailableError),
        (500, RecordFailedError),
        (507, RecordFailedError),
    ],
)
def test_every_answer_tells_the_outbox_what_to_do(status: int, error: type[StoreError]) -> None:
    transport = httpx.MockTransport(lambda _: httpx.Response(status, json={"detail": "no"}))
    with (
        HttpStore("http://results", "key", transport=transport) as store,
        pytest.raises(StoreError) as raised,
    ):
        store.submit(make_record())
    assert type(raised.value) is error
    assert str(status) in str(raised.value)


def test_both_stores_hand_the_station_a_units_stored_gyro_fit(
    live_url: str, database: Database, station_key: str
) -> None:
    log, _ = simulate_log(paper_truth(), seed=3)
    fit = GyroFitRecord(
        serial="PT000031", fitted_at=datetime(2026, 1, 1, tzinfo=UTC), source="c.csv",
        report=fit_log(log),
    )  # fmt: skip
    with database.session() as session, session.begin():
        RunRepository(session).add_gyro_fit(fit)
    with HttpStore(live_url, station_key) as http:
        stores = (DatabaseStore(database=database), http)
        for store in stores:
            held = store.gyro_fit("PT000031")
            assert held is not None
            assert held.report.g_sensitivity_ppm_per_g == fit.report.g_sensitivity_ppm_per_g
            assert store.gyro_fit("PT000032") is None
