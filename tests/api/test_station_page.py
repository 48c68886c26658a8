"""A station's health page over a live server: golden checks against their baseline,
the drift warning worked out here, cycle times and versions from the runs stored."""

import re
from datetime import timedelta

import httpx
import numpy as np

from db import Database, RunRepository
from tests.db.records import T0, make_record
from tests.servers import local_get, serving

#: The golden unit's offset x per check: baseline the mean of the first three (2049).
GOLDEN_X = [2048.0, 2049.0, 2050.0, 2051.0, 2057.0]
#: Production runs: seconds from start to finish, software version.
PRODUCTION = [(90, "1.4.0"), (95, "1.4.0"), (100, "1.5.0"), (130, "1.5.0")]


def _store(database: Database, golden: list[float]) -> None:
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        for i, x in enumerate(golden):
            started = T0 + timedelta(hours=8 * i)
            repository.submit(
                make_record(
                    serial="GOLD-01",
                    station_id="line1-st1",
                    started_at=started,
                    offset=(x, 2041.2, 1960.5),
                    purpose="golden",
                )
            )
        for i, (cycle, version) in enumerate(PRODUCTION):
            started = T0 + timedelta(hours=8 * i + 1)
            repository.submit(
                make_record(
                    serial=f"PT{i:06d}",
                    station_id="line1-st1",
                    started_at=started,
                    finished_at=(started + timedelta(seconds=cycle)).isoformat(),
                    software_version=version,
                )
            )


def test_a_station_page_shows_golden_drift_cycle_times_and_versions(
    client: httpx.Client, database: Database
) -> None:
    _store(database, GOLDEN_X)
    health = client.get("/stations/line1-st1", params={"format": "json"}).json()
    baseline = np.mean(GOLDEN_X[:3])
    deviations = [c["offset_deviation"][0] for c in health["golden"]]
    assert np.allclose(deviations, [x - baseline for x in GOLDEN_X])
    assert np.allclose(health["golden"][-1]["sensitivity_deviation"], 0.0, atol=1e-6)
    [drift] = health["drift"]
    assert drift["serial"] == "GOLD-01"
    assert drift["problem"].startswith("offset x +8.00 counts from its baseline")
    assert drift["checked_at"] == (T0 + timedelta(hours=8 * 4)).isoformat().replace("+00:00", "Z")
    cycles = [c for c, _ in PRODUCTION]
    cycle = health["cycle_seconds"]
    assert cycle["n"] == len(cycles)
    assert np.isclose(cycle["mean"], np.mean(cycles))
    assert np.isclose(cycle["median"], np.median(cycles))
    assert {(v["software_version"], v["runs"]) for v in health["versions"]} == {
        ("1.4.0", 2),
        ("1.5.0", 2),
    }
    page = client.get("/stations/line1-st1")
    assert page.status_code == 200
    assert page.text.count('<tr class="golden-check">') == len(GOLDEN_X)
    # A deviation is shown to the hundredth: a baseline's rounding error reads 0.
    row = r'<tr class="golden-check">.*?<td>([^<]*)</td>\s*<td>([^<]*)</td>'
    cells = re.findall(row, page.text, flags=re.S)
    shown = [value for row in cells for cell in row for value in cell.split(", ")]
    assert len(shown) == 6 * len(GOLDEN_X)
    assert [value for value in shown if "e" in value or value == "-0"] == []
    assert len(re.findall(r'<p class="problem drift">', page.text)) == 1
    assert page.text.count('<tr class="version">') == 2
    assert '<rect class="box"' in page.text


def test_a_station_within_tolerance_has_no_drift_and_an_unknown_one_is_a_404_page(
    client: httpx.Client, database: Database
) -> None:
    _store(database, GOLDEN_X[:4])
    page = client.get("/stations/line1-st1")
    assert 'class="ok no-drift"' in page.text
    assert client.get("/stations/line1-st1", params={"format": "json"}).json()["drift"] == []
    missing = client.get("/stations/line9-st9")
    assert missing.status_code == 404
    assert missing.headers["content-type"].startswith("text/html")
    assert client.get("/stations/bad station").status_code == 422


def test_a_drift_warning_tells_its_check_in_the_plants_time_zone(
    database: Database, database_url: str
) -> None:
    """UTC+14: the latest check, 2026-11-03 16:00 UTC, is 11-04 06:00 in the plant; the
    warning says so, as the table of checks does, never UTC in a plant-zone page."""
    _store(database, GOLDEN_X)
    with serving(database_url, plant_timezone="Pacific/Kiritimati") as base:
        page = local_get(f"{base}/stations/line1-st1").text
    [warning] = re.findall(r'<p class="problem drift">(.*?)</p>', page)
    assert "(checked 2026-11-04 06:00" in warning
    assert "16:00" not in warning
