"""``GET /metrics``: the server's Prometheus metrics, scraped from a real server and parsed.

Every count asserted here is what the test itself caused: on the worker's shared server
(whose tests run one at a time) the difference of a scrape before and one after; where
the server's own shape is the subject (two worker processes), on a server of its own.
"""

import uuid

import httpx
from prometheus_client.parser import text_string_to_metric_families

from api.main import create_app
from api.metrics import documented_paths
from api.settings import ApiSettings
from db import Database, RunRepository
from tests.db.records import make_record
from tests.servers import local_client, serving

RUNS = "/api/v1/runs"


def scrape(client: httpx.Client) -> dict[tuple[str, tuple[tuple[str, str], ...]], float]:
    """Every sample of ``/metrics``: (name, sorted labels) → value."""
    answer = client.get("/metrics")
    assert answer.status_code == 200
    assert answer.headers["content-type"].startswith("text/plain")
    return {
        (sample.name, tuple(sorted(sample.labels.items()))): sample.value
        for family in text_string_to_metric_families(answer.text)
        for sample in family.samples
    }


def value(
    samples: dict[tuple[str, tuple[tuple[str, str], ...]], float], name: str, **labels: str
) -> float:
    return samples.get((name, tuple(sorted(labels.items()))), 0.0)


def _key(database: Database, station: str) -> dict[str, str]:
    with database.session() as session, session.begin():
        return {"Authorization": f"Bearer {RunRepository(session).create_key(station)}"}


def counted(
    before: dict[tuple[str, tuple[tuple[str, str], ...]], float],
    after: dict[tuple[str, tuple[tuple[str, str], ...]], float],
) -> dict[tuple[str, tuple[tuple[str, str], ...]], float]:
    """What each counter counted between two scrapes (the series that moved)."""
    return {key: v - before.get(key, 0.0) for key, v in after.items() if v != before.get(key)}


def test_stored_runs_refusals_and_requests_are_counted(
    database: Database, client: httpx.Client
) -> None:
    st1, st2 = _key(database, "line1-st1"), _key(database, "line1-st2")
    before = scrape(client)
    passed = make_record(serial="PT-100001")
    failed = make_record(serial="PT-100002", verdict="fail", coefficients=None, quality=None)
    other = make_record(  # a DIXX-D16 unit: 16-bit counts, 8 192 counts/g
        serial="PT-100003",
        station_id="line1-st2",
        part_number="DIXX-D16",
        offset=(33010.5, 32540.25, 31980.0),
        sensitivity=(8150.0, 8240.5, 8190.0),
    )
    for record, key in ((passed, st1), (failed, st1), (other, st2)):
        body = record.model_dump(mode="json")
        assert client.post(RUNS, json=body, headers=key).status_code == 201
    # A retry is answered 200 and not counted again.
    assert client.post(RUNS, json=passed.model_dump(mode="json"), headers=st1).status_code == 200
    # Refused: another station's run, no key, a clash, a body that is not a run.
    assert client.post(RUNS, json=other.model_dump(mode="json"), headers=st1).status_code == 403
    assert client.post(RUNS, json=passed.model_dump(mode="json")).status_code == 401
    clash = passed.model_copy(update={"operator_id": "op-9"}).model_dump(mode="json")
    assert client.post(RUNS, json=clash, headers=st1).status_code == 409
    assert client.post(RUNS, json={"serial": "x"}, headers=st1).status_code == 422
    run_id = uuid.uuid4()
    assert client.get(f"{RUNS}/{run_id}").status_code == 404
    assert client.get(f"{RUNS}/{passed.run_id}").status_code == 200
    assert client.get("/no/such/page").status_code == 404

    after = scrape(client)
    samples = counted(before, after)

    stored = "calstation_runs_stored_total"
    a12, d16 = {"part_number": "DIXX-A12"}, {"part_number": "DIXX-D16"}
    assert value(samples, stored, station="line1-st1", verdict="pass", **a12) == 1
    assert value(samples, stored, station="line1-st1", verdict="fail", **a12) == 1
    assert value(samples, stored, station="line1-st2", verdict="pass", **d16) == 1
    assert sum(v for (name, _), v in samples.items() if name == stored) == 3

    refused = "calstation_run_submissions_refused_total"
    assert {
        dict(labels)["reason"]: v for (name, labels), v in samples.items() if name == refused
    } == {
        "wrong_station": 1,
        "unauthorized": 1,
        "conflict": 1,
        "invalid": 1,
    }

    requests = "calstation_http_requests_total"
    by_route = {
        (d["route"], d["method"], d["status"]): v
        for (name, labels), v in samples.items()
        if name == requests
        for d in [dict(labels)]
    }
    # Route templates, never raw paths: the two reads of single runs share one series each.
    assert by_route[("/api/v1/runs/{run_id}", "GET", "404")] == 1
    assert by_route[("/api/v1/runs/{run_id}", "GET", "200")] == 1
    assert by_route[(RUNS, "POST", "201")] == 3
    assert by_route[(RUNS, "POST", "200")] == 1
    assert by_route[("<unmatched>", "GET", "404")] == 1
    assert not any(str(passed.run_id) in route for route, _, _ in by_route)

    latency = "calstation_http_request_duration_seconds_count"
    assert value(samples, latency, route=RUNS, method="POST") == 8
    assert value(after, "calstation_report_pool_processes") == 1
    assert value(after, "calstation_report_pool_busy") == 0


def test_a_report_counts_in_the_report_pool_and_every_worker_is_added_up(
    database: Database, database_url: str
) -> None:
    st1 = _key(database, "line1-st1")
    with (
        serving(database_url, workers=2) as base,
        local_client(base, timeout=60) as client,
    ):
        for n in range(6):
            # A client each: new connections, spread over the workers by the kernel.
            body = make_record(serial=f"PT-2000{n:02d}").model_dump(mode="json")
            with local_client(base, timeout=60) as own:
                assert own.post(RUNS, json=body, headers=st1).status_code == 201
        assert client.get("/api/v1/reports/eol").status_code == 200
        # Whichever worker answers a scrape, it shows every worker's counts.
        scrapes = [scrape(client) for _ in range(4)]

    for samples in scrapes:
        assert (
            value(
                samples,
                "calstation_runs_stored_total",
                station="line1-st1",
                verdict="pass",
                part_number="DIXX-A12",
            )
            == 6
        )
        assert value(samples, "calstation_report_pool_processes") == 2  # one per worker
        assert value(samples, "calstation_report_pool_busy") == 0
        eol = value(
            samples,
            "calstation_http_request_duration_seconds_count",
            route="/api/v1/reports/eol",
            method="GET",
        )
        assert eol == 1


def test_the_openapi_document_names_the_metrics_answer(client: httpx.Client) -> None:
    operation = client.get("/openapi.json").json()["paths"]["/metrics"]["get"]
    assert list(operation["responses"]["200"]["content"]) == ["text/plain"]


def test_the_route_templates_are_the_documents_paths_in_its_order() -> None:
    """Requests are labelled by the paths of the OpenAPI document, read off the routes
    without building it: the two agree, so an upgrade of FastAPI that walks its routes
    otherwise is caught here."""
    app = create_app(ApiSettings())
    assert documented_paths(app) == list(app.openapi()["paths"])
