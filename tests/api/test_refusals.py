"""Nonsense is refused before it reaches SQL: 422 naming the field or parameter, never
500, on SQLite and PostgreSQL (a real server process on each)."""

from collections.abc import Callable
from datetime import UTC, datetime, timedelta
from importlib import resources
from typing import Any

import httpx
import pytest

from station.domain.quality.days import day_start
from station.domain.record.records import document_sha256
from tests.db.records import make_record

RUNS = "/api/v1/runs"
EOL = "/api/v1/reports/eol"
#: Seconds a report may take before a test gives up on it (not a bound it must meet).
SAFETY_S = 120


def _auth(key: str) -> dict[str, str]:
    return {"Authorization": f"Bearer {key}"}


@pytest.mark.parametrize(
    ("change", "loc", "words"),
    [
        (lambda body: body["poses"][0]["std"].update(x=1e300), "body.poses.0.std", "x 1e+300"),
        (
            lambda body: body.update(
                gyro={"bias": {"x": 1e300, "y": 0, "z": 0}, "noise": {"x": 1, "y": 1, "z": 1}}
            ),
            "body.gyro.bias",
            "gyro range",
        ),
        (
            lambda body: body["poses"][1].update(temperature_c=-1e300),
            "body.poses.1.temperature_c",
            "greater than or equal",
        ),
        (
            lambda body: body["poses"][2]["mean"].update(y=4096.0),
            "body.poses",
            "poses.2.mean: y 4096 outside the ADC range 0…4095",
        ),
    ],
    ids=["pose-std", "gyro-bias", "temperature", "beyond-its-sensor"],
)
def test_a_poison_run_is_refused_naming_the_field_and_the_report_still_answers(
    client: httpx.Client, station_key: str, change: object, loc: str, words: str
) -> None:
    good = make_record()
    assert client.post(
        RUNS, json=good.model_dump(mode="json"), headers=_auth(station_key)
    ).is_success
    body = make_record(serial="PT-000002").model_dump(mode="json")
    change(body)  # type: ignore[operator]
    answer = client.post(RUNS, json=body, headers=_auth(station_key))
    assert answer.status_code == 422, answer.text
    errors = answer.json()["errors"]
    assert errors[0]["loc"] == loc
    assert words in errors[0]["msg"]
    assert loc in answer.json()["detail"]
    report = client.get(EOL)
    assert report.status_code == 200, report.text
    assert report.json()["summary"]["runs"] == 1


def _with_profile(body: dict[str, Any], field: str, bounds: dict[str, float | None]) -> None:
    """Give the run of ``body`` its limits profile with ``field`` set to ``bounds``, hashed
    as a station would hash it (so only the bounds themselves can be refused)."""
    profile = {**body["limits"]["profile"], field: bounds}
    body["limits"] = {**body["limits"], "profile": profile, "sha256": document_sha256(profile)}


@pytest.mark.parametrize(
    ("field", "bounds"),
    [
        ("offset_counts", {"lower": 1841.0, "upper": 1e300}),
        ("pose_noise_counts", {"lower": None, "upper": 1e308}),
        ("gyro_bias_dps", {"lower": -1e308, "upper": 10.0}),
        ("verification_error_mg", {"lower": -1e200, "upper": 30.0}),
    ],
    ids=["offset-1e300", "pose-noise-1e308", "gyro-bias-minus-1e308", "verification-minus-1e200"],
)
def test_a_run_whose_limits_profile_has_absurd_bounds_is_refused_and_the_reports_answer(
    client: httpx.Client, station_key: str, field: str, bounds: dict[str, float | None]
) -> None:
    today = day_start(datetime.now(UTC), "UTC")  # in the dashboard's range too
    good = make_record(started_at=today)
    assert client.post(
        RUNS, json=good.model_dump(mode="json"), headers=_auth(station_key)
    ).is_success
    body = make_record(serial="PT-000002", started_at=today).model_dump(mode="json")
    _with_profile(body, field, bounds)
    answer = client.post(RUNS, json=body, headers=_auth(station_key))
    assert answer.status_code == 422, answer.text
    error = answer.json()["errors"][0]
    assert error["loc"] == "body.limits.profile"
    assert field in error["msg"]
    assert field in answer.json()["detail"]
    for fmt in ("json", "csv", "html"):
        # The first report starts the server's report processes: a generous safety net.
        report = client.get(EOL, params={"format": fmt}, timeout=SAFETY_S)
        assert report.status_code == 200, (fmt, report.text)
    assert client.get(EOL, timeout=SAFETY_S).json()["summary"]["runs"] == 1
    dashboard = client.get("/", timeout=SAFETY_S)
    assert dashboard.status_code == 200, dashboard.text
    assert "PT-000001" in dashboard.text


def _failure_message(body: dict[str, Any], text: str) -> None:
    body.update(verdict="fail", failures=[{"code": "offset", "message": text}])


def _capture_reason(body: dict[str, Any], text: str) -> None:
    body["poses"][0]["replaced"][0]["reason"] = text


def _description(body: dict[str, Any], text: str) -> None:
    profile = {**body["limits"]["profile"], "description": text}
    body["limits"] = {**body["limits"], "profile": profile, "sha256": document_sha256(profile)}


@pytest.mark.parametrize(
    ("change", "text", "loc"),
    [
        (_failure_message, "offset x out of limits\n", "body.failures.0.message"),
        (_capture_reason, "moved during capture\n", "body.poses.0.replaced.0.reason"),
        (_description, "KXM52\x00production", "body.limits.profile"),
    ],
    ids=[
        "failure-message-trailing-newline",
        "capture-reason-trailing-newline",
        "nul-in-description",
    ],
)
def test_a_run_with_a_control_character_in_its_text_is_refused_naming_the_field(
    client: httpx.Client,
    station_key: str,
    change: Callable[[dict[str, Any], str], None],
    text: str,
    loc: str,
) -> None:
    body = make_record().model_dump(mode="json")
    change(body, text)
    answer = client.post(RUNS, json=body, headers=_auth(station_key))
    assert answer.status_code == 422, answer.text
    assert answer.json()["errors"][0]["loc"] == loc
    assert "control characters" in answer.json()["detail"]
    assert client.get(RUNS).json()["count"] == 0


#: The shipped limits file, its first profile's offsets replaced by ``{OFFSETS}``.
SHIPPED_WITH_OFFSETS = (
    resources.files("station.domain.profiles")
    .joinpath("limits.toml")
    .read_text(encoding="utf-8")
    .replace("offset_counts = { lower = 1841.0, upper = 2255.0 }", "offset_counts = {OFFSETS}", 1)
)


@pytest.mark.parametrize(
    ("content", "words"),
    [
        ('[profiles.deep]\nversion = "1"\nx = ' + "[" * 900 + "]" * 900, "nested too deeply"),
        ("[profiles]\nx = 1\n", "profiles.x is not a table"),
        ("x = " + "9" * 4301, "Exceeds the limit (4300 digits) for integer string conversion"),
        (
            SHIPPED_WITH_OFFSETS.replace("{OFFSETS}", "{ lower = -1e308, upper = 1e308 }"),
            "profile kxm52-production: offset_counts: Value error, lower -1e+308 outside",
        ),
    ],
    ids=["nested-900-deep", "profile-not-a-table", "integer-4301-digits", "bounds-1e308"],
)
def test_an_unusable_what_if_file_is_422_with_one_line_naming_the_problem(
    client: httpx.Client, station_key: str, content: str, words: str
) -> None:
    stored = client.post(
        RUNS, json=make_record().model_dump(mode="json"), headers=_auth(station_key)
    )
    assert stored.is_success
    upload = {"limits": ("candidate.toml", content.encode())}
    answer = client.post(EOL, params={"format": "json"}, files=upload, timeout=SAFETY_S)
    assert answer.status_code == 422, answer.text
    detail = answer.json()["detail"]
    assert detail.startswith("invalid request: body.limits: candidate.toml: ")
    assert words in detail
    assert "\n" not in detail
    assert answer.json()["errors"][0]["loc"] == "body.limits"


@pytest.mark.parametrize(
    ("query", "loc"),
    [
        (f"{RUNS}?station_id=%00", "query.station_id"),
        (f"{RUNS}?lot=%00", "query.lot"),
        (f"{RUNS}?lot={'x' * 65}", "query.lot"),
        (f"{RUNS}?cursor=%00", "query.cursor"),
        (f"{EOL}?station=%00", "query.station"),
        (f"{EOL}?operator=%00", "query.operator"),
        (f"{EOL}?lot=%00", "query.lot"),
        (f"{EOL}?from=9999-12-31T23:00:00-05:00", "query.from"),
        (f"{EOL}?to=0001-01-01T00:00:00%2B01:00", "query.to"),
        (f"{EOL}?units=999999999999999999999", "query.units"),
        (f"{EOL}?units=1000001", "query.units"),
        (f"{EOL}?from=2026-11-03&to=2026-11-02", "query.from"),
    ],
)
def test_every_unusable_query_parameter_gets_422_naming_it(
    client: httpx.Client, query: str, loc: str
) -> None:
    answer = client.get(query)
    assert answer.status_code == 422, answer.text
    assert answer.json()["errors"][0]["loc"] == loc
    assert answer.json()["detail"].startswith(f"invalid request: {loc}: ")


@pytest.mark.parametrize(
    "query",
    [
        f"{EOL}?from=9999-12-31",
        f"{EOL}?to=0001-01-02",
        f"{EOL}?from=0001-01-02T00:00:00Z&to=9999-12-31T00:00:00Z",
        f"{EOL}?from=0001-01-01T00:00:00Z&to=9999-12-31T23:59:59.999999Z",
        f"{EOL}?from=9999-12-31T23:59:59Z",
        f"{EOL}?units=1000&page=1000000&format=csv",
        f"{RUNS}?since=0001-01-01T00:00:00Z&until=9999-12-31T23:59:59Z",
    ],
)
def test_the_edges_of_the_ranges_are_answered(client: httpx.Client, query: str) -> None:
    assert client.get(query).status_code == 200


def test_a_forged_cursor_that_overflows_is_400_not_500(client: httpx.Client) -> None:
    import base64

    forged = base64.urlsafe_b64encode(b"0001-01-01T00:00:00+14:00|5").decode().rstrip("=")
    answer = client.get(RUNS, params={"cursor": forged})
    assert answer.status_code == 400, answer.text
    assert "cursor" in answer.json()["detail"]


#: The last moment a time can hold: SQLite's date functions round it into the year 10000.
LAST_MOMENT = datetime(9999, 12, 31, 23, 59, 59, 999999, tzinfo=UTC)


@pytest.mark.parametrize(
    ("started_at", "finished_at", "loc"),
    [
        (datetime(1, 1, 1, tzinfo=UTC), None, "body.started_at"),
        (LAST_MOMENT - timedelta(seconds=95), LAST_MOMENT, "body.started_at"),
        (
            datetime(2199, 12, 31, 23, 59, tzinfo=UTC),
            datetime(2200, 1, 1, tzinfo=UTC),
            "body.finished_at",
        ),
        (
            datetime(1999, 12, 31, 23, 59, tzinfo=UTC),
            datetime(2000, 1, 1, tzinfo=UTC),
            "body.started_at",
        ),
    ],
    ids=["year-1", "end-of-9999", "into-2200", "from-1999"],
)
def test_a_run_stamped_outside_the_years_2000_to_2199_is_refused_naming_the_field(
    client: httpx.Client,
    station_key: str,
    started_at: datetime,
    finished_at: datetime | None,
    loc: str,
) -> None:
    stored = make_record(started_at=datetime(2000, 1, 1, tzinfo=UTC))
    answer = client.post(RUNS, json=stored.model_dump(mode="json"), headers=_auth(station_key))
    assert answer.status_code == 201, answer.text
    moved = {"finished_at": finished_at.isoformat()} if finished_at else {}
    body = make_record(started_at=started_at, **moved).model_dump(mode="json")
    answer = client.post(RUNS, json=body, headers=_auth(station_key))
    assert answer.status_code == 422, answer.text
    [error] = answer.json()["errors"]
    assert error["loc"] == loc
    assert "outside the years 2000…2199 (UTC)" in error["msg"]
    report = client.get(EOL, params={"from": "2000-01-01", "to": "2000-01-02"})
    assert report.status_code == 200, report.text
    assert report.json()["summary"]["runs"] == 1
    assert client.get(f"/api/v1/units/{stored.serial}").json()["attempts"] == 1
