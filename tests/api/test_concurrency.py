"""Many stations at once on PostgreSQL: every run stored exactly once, retries and all."""

import threading
import uuid
from collections import Counter
from concurrent.futures import ThreadPoolExecutor
from datetime import timedelta

import pytest
from sqlalchemy import func, select

from db import Database
from db.models import Run, RunPose
from station.domain.record.records import RunRecord
from station.results.storage import DatabaseStore, HttpStore, RunStore, StoreUnavailableError
from tests.conftest import NIGHTLY
from tests.db.records import T0, make_record
from tests.servers import STATION

SUBMITTERS = 20
#: Runs of each submitter's own batch: the nightly profile stores 2,000 of them (2,400
#: submissions with the retries); ``make test`` a quarter, the same twenty stations racing.
RUNS_EACH = 50 if NIGHTLY else 12

on_postgresql = pytest.mark.parametrize(
    "database_url", [pytest.param("postgresql", marks=pytest.mark.postgres)], indirect=True
)


def _submit_with_retries(store: RunStore, record: RunRecord) -> bool:
    for _ in range(5):
        try:
            return store.submit(record).created
        except StoreUnavailableError:
            continue
    return store.submit(record).created


def _assert_stored_once(
    database: Database, expected: set[uuid.UUID], created: Counter[uuid.UUID], poses_each: int
) -> None:
    assert set(created) == expected
    assert set(created.values()) == {1}
    with database.session() as session:
        stored = Counter(session.scalars(select(Run.run_id)))
        poses = session.scalar(select(func.count()).select_from(RunPose))
    assert stored == Counter(expected)
    assert poses == len(expected) * poses_each


@on_postgresql
# At night 2,000 serialised submissions: a minute on a busy 2-core machine, more under
# heavy load. The timeout is only a safety net against a hang, never a speed assertion.
@pytest.mark.timeout(900)
def test_concurrent_submitters_store_every_run_exactly_once(database: Database) -> None:
    batches = [
        [
            make_record(
                serial=f"PT-{k:02d}{i:04d}", started_at=T0 + timedelta(seconds=k * RUNS_EACH + i)
            )
            for i in range(RUNS_EACH)
        ]
        for k in range(SUBMITTERS)
    ]
    url = database.engine.url.render_as_string(hide_password=False)

    def submitter(k: int) -> list[tuple[uuid.UUID, bool]]:
        # A station of its own (its own connection), submitting its batch interleaved
        # with its neighbour's backwards (racing the neighbour), and retrying every fifth
        # run at once as if the first answer had been lost.
        mine, theirs = batches[k], batches[(k + 1) % SUBMITTERS][::-1]
        results = []
        with DatabaseStore(url) as store:
            for n, record in enumerate(r for pair in zip(mine, theirs, strict=True) for r in pair):
                results.append((record.run_id, _submit_with_retries(store, record)))
                if n % 5 == 0:
                    results.append((record.run_id, _submit_with_retries(store, record)))
        return results

    with ThreadPoolExecutor(SUBMITTERS) as pool:
        results = [pair for batch in pool.map(submitter, range(SUBMITTERS)) for pair in batch]

    created = Counter(run_id for run_id, was_created in results if was_created)
    expected = {record.run_id for batch in batches for record in batch}
    _assert_stored_once(database, expected, created, len(batches[0][0].poses))


@on_postgresql
def test_simultaneous_duplicates_over_http_get_one_201(
    live_url: str, database: Database, station_key: str
) -> None:
    records = [make_record(serial=f"PT-9{i:05d}", station_id=STATION) for i in range(5)]
    start = threading.Barrier(SUBMITTERS)

    def submitter(_: int) -> list[tuple[uuid.UUID, bool]]:
        with HttpStore(live_url, station_key, timeout=30) as store:
            start.wait()
            return [(r.run_id, _submit_with_retries(store, r)) for r in records]

    with ThreadPoolExecutor(SUBMITTERS) as pool:
        results = [pair for batch in pool.map(submitter, range(SUBMITTERS)) for pair in batch]

    created = Counter(run_id for run_id, was_created in results if was_created)
    _assert_stored_once(database, {r.run_id for r in records}, created, len(records[0].poses))
