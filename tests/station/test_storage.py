"""The station's run stores: straight into the database, or over HTTP to a live server."""

import httpx
import pytest

from db import Database, RunRepository
from station.storage import (
    DatabaseStore,
    HttpStore,
    StoreUnavailableError,
    SubmissionRefusedError,
)
from tests.db.records import make_record
from tests.servers import free_port


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
    unit = httpx.get(f"{live_url}/api/v1/units/{record.serial}").json()
    assert unit["latest"]["run_id"] == unit["holds"]["run_id"] == str(record.run_id)


def test_the_http_store_tells_a_refusal_from_an_outage(
    live_url: str, database: Database, station_key: str
) -> None:
    with (
        HttpStore(live_url, "csk_wrong") as store,
        pytest.raises(SubmissionRefusedError, match="401"),
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
