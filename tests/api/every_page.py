"""Every page of the results server over one plant's runs, for the tests that read each
page in every language and at every width: the dashboard, the report, a unit's page, a
station's, the alerts, a split and a Pareto bar's failing runs."""

from datetime import UTC, datetime, timedelta

from db import Database, RunRepository
from db.models import StoredAlert
from station.domain.product.limits import Bounds, check, load_profile
from tests.db.records import make_record

#: A unit that failed twice, then passed; its station; a golden unit of that station.
SERIAL, STATION, GOLDEN = "PT-WIDE-001", "line1-station-1", "GOLD-01"
#: Every page, by name: the address of each.
PAGES = {
    "dashboard": "/",
    "report": "/api/v1/reports/eol?format=html&list=all",
    "unit": f"/units/{SERIAL}",
    "held unit": "/units/PT-000003",
    "station": f"/stations/{STATION}",
    "alerts": "/alerts",
    "split": "/api/v1/reports/split?parameter=offset_x&by=station",
    "failures": "/api/v1/reports/eol/failures?code=pose_noise",
    "search": "/search?serial=PT-00",
}


def store_plant(database: Database) -> None:
    """Today's runs of two stations (passes, failures with their values and limits, a
    unit retested, units on hold), golden-unit checks drifting away, and an outbox alert."""
    now = datetime.now(UTC).replace(microsecond=0)
    start = max(now - timedelta(minutes=40), now.replace(hour=0, minute=0, second=0))
    profile = load_profile().model_copy(update={"pose_noise_counts": Bounds(upper=8.0)})
    failure = check(profile, "pose_noise", 8.59057, axis="x", pose=2)
    assert failure is not None
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        for i, x in enumerate((2048.0, 2049.0, 2050.0, 2058.0)):
            repository.submit(
                make_record(
                    serial=GOLDEN,
                    station_id=STATION,
                    started_at=start - timedelta(days=3 - i),
                    offset=(x, 2041.2, 1960.5),
                    purpose="golden",
                )
            )
        for i in range(12):
            failed = i % 3 == 0 and i < 9
            repository.submit(
                make_record(
                    serial=SERIAL if i < 3 else f"PT-{i:06d}",
                    station_id=f"line1-station-{1 + i % 2}",
                    operator_id="operator-with-a-long-name",
                    verdict="fail" if failed else "pass",
                    failures=[failure.model_dump(), failure.model_dump()] if failed else [],
                    lot="LOT-2026-11-A",
                    started_at=start + timedelta(minutes=2 * i),
                    finished_at=(start + timedelta(minutes=2 * i, seconds=95 + i)).isoformat(),
                    offset=(2081.9 + i, 2041.2 - i, 1960.5 + 0.5 * i),
                )
            )
        session.add(
            StoredAlert(
                event_key="outbox:line1-station-2:0:1",
                watch="outbox:line1-station-2",
                rule="outbox",
                scope="line1-station-2",
                message="outbox of line1-station-2: 3 runs queued",
                evidence={
                    "queued": 3,
                    "oldest_s": 7300,
                    "set_aside": 1,
                    "reported_at": start.isoformat(),
                },
                fired_at=start + timedelta(minutes=30),
                attempts=1,
                next_attempt_at=start + timedelta(minutes=30),
            )
        )
