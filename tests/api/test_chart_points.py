"""The report's control charts over the chosen period or lot: ``points=`` plots more of
its latest runs than the default, the lot's own runs when a lot is chosen."""

from datetime import timedelta
from typing import Any

import httpx

from db import Database, RunRepository
from tests.db.records import T0, make_record


def test_control_charts_plot_the_latest_points_of_the_period_or_lot(
    client: httpx.Client, database: Database
) -> None:
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        for i in range(30):
            repository.submit(
                make_record(
                    serial=f"PT{i:06d}",
                    started_at=T0 + timedelta(minutes=5 * i),
                    offset=(2080.0 + i % 7, 2041.2, 1960.5),
                    lot="lot-a" if i < 12 else "lot-b",
                )
            )

    def charts(**query: object) -> list[dict[str, Any]]:
        answer = client.get("/api/v1/reports/eol", params=query)
        assert answer.status_code == 200, answer.text
        found: list[dict[str, Any]] = answer.json()["control_charts"]
        return found

    assert {len(c["points"]) for c in charts()} == {30}
    chosen = charts(points=10)
    assert {len(c["points"]) for c in chosen} == {10}
    assert all(c["count"] == 30 for c in chosen)
    lot = charts(points=10, lot="lot-a")
    assert {len(c["points"]) for c in lot} == {10}
    assert all(c["count"] == 12 for c in lot)
    refused = client.get("/api/v1/reports/eol", params={"points": 5, "format": "html"})
    assert refused.status_code == 422
    assert 'id="problem"' in refused.text
    page = client.get("/api/v1/reports/eol", params={"format": "html", "lot": "lot-a"}).text
    more = 'class="more-points" href="/api/v1/reports/eol?lot=lot-a&amp;format=html&amp;list=held'
    assert more + '&amp;points=1000"' in page
