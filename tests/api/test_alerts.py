"""Alerts on a live server, posted to a real webhook receiver (a small HTTP server of
the test): an event is posted once, not again on later rounds nor after a restart with
two server processes, again once it cleared and fired anew; a receiver that was down
gets it once it is back, once. Rounds are waited for on the server's own count, never
on the clock."""

import json
import os
import threading
from collections.abc import Iterator
from datetime import UTC, datetime, timedelta
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest
from sqlalchemy import select

from db import Database, RunRepository
from db.models import StationOutbox
from station.domain.record.outbox_report import OUTBOX_HEADER
from station.results.backoff import RecordBackoff
from station.results.outbox import Outbox
from station.results.storage import HttpStore
from tests.conftest import CliRunner
from tests.db.records import T0, make_record
from tests.servers import HUNG_SERVER_S, STATION, local_get, serving

#: The rule: first-pass yield of st1's last 4 units below 75 %.
RULES = """
webhook = "{webhook}"

[[yield]]
station = "st1"
units = 4
goal = 0.75
"""
#: A safety net for a wait, not a speed requirement.
PATIENCE_S = 60.0
#: The servers' alert interval, and how often a test asks how far their loops got:
#: asking more often than a loop goes round only costs both processes CPU.
ALERT_INTERVAL_S = 0.2


class Receiver:
    """A webhook: takes JSON posts (or, while ``down``, answers 503 and keeps nothing)."""

    def __init__(self) -> None:
        self.received: list[dict[str, Any]] = []
        self.refused = 0
        self.down = False
        #: Seconds it takes to answer a post it keeps (a slow chat server).
        self.delay_s = 0.0
        self.changed = threading.Condition()
        receiver = self

        class Handler(BaseHTTPRequestHandler):
            def do_POST(self) -> None:
                body = self.rfile.read(int(self.headers["Content-Length"]))
                if not receiver.down:
                    threading.Event().wait(receiver.delay_s)
                with receiver.changed:
                    if receiver.down:
                        receiver.refused += 1
                        self.send_response(503)
                    else:
                        receiver.received.append(json.loads(body))
                        self.send_response(204)
                    receiver.changed.notify_all()
                self.end_headers()

            def log_message(self, format: str, *args: Any) -> None:
                pass

        self.server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.url = f"http://127.0.0.1:{self.server.server_address[1]}/hook"
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def wait(self, what: str, check: Any) -> None:
        with self.changed:
            if not self.changed.wait_for(check, timeout=PATIENCE_S):
                raise AssertionError(f"the receiver saw no {what}")


@pytest.fixture
def receiver() -> Iterator[Receiver]:
    found = Receiver()
    yield found
    found.server.shutdown()
    found.server.server_close()


def _store(database: Database, verdicts: str, start: int) -> None:
    """Units at st1, one per letter of ``verdicts`` (p pass, f fail), from minute ``start``."""
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        for i, letter in enumerate(verdicts):
            repository.submit(
                make_record(
                    serial=f"PT{start + i:06d}",
                    station_id="st1",
                    started_at=T0 + timedelta(minutes=start + i),
                    verdict="pass" if letter == "p" else "fail",
                )
            )


def _store_offsets(
    database: Database, values: list[float], start: int, station_id: str = "line1-st1"
) -> None:
    """Units at ``station_id``, one run each with these offset_x ``values``, a minute
    apart from minute ``start``."""
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        for i, value in enumerate(values):
            repository.submit(
                make_record(
                    serial=f"PT{start + i:06d}",
                    station_id=station_id,
                    started_at=T0 + timedelta(minutes=start + i),
                    offset=(value, 2041.2, 1960.5),
                )
            )


def _alerts(base: str) -> dict[str, Any]:
    answer = local_get(f"{base}/alerts", params={"format": "json"})
    assert answer.status_code == 200, answer.text
    found: dict[str, Any] = answer.json()
    return found


def _rounds_later(base: str, rounds: int = 2, processes: int = 1) -> dict[str, Any]:
    """The alerts once ``processes`` server processes have each done ``rounds`` rounds
    more than when first asked (each process counts its own)."""
    first: dict[int, int] = {}
    done: set[int] = set()
    for _ in range(int(PATIENCE_S / ALERT_INTERVAL_S)):
        now = _alerts(base)
        process, done_rounds = now["process"], now["rounds"]
        if done_rounds >= first.setdefault(process, done_rounds) + rounds:
            done.add(process)
        if len(done) >= processes:
            return now
        threading.Event().wait(ALERT_INTERVAL_S)
    raise AssertionError("the alert loop did no rounds")


def _settings(tmp_path: Path, receiver: Receiver, rules_text: str = RULES) -> dict[str, str]:
    """The server's settings for ``rules_text`` (``{webhook}``: the receiver's address),
    checked every :data:`ALERT_INTERVAL_S`, a refused post tried again after 0.5 s."""
    rules = tmp_path / "alerts.toml"
    rules.write_text(rules_text.format(webhook=receiver.url))
    return {
        "alerts_file": str(rules),
        "alert_interval_s": str(ALERT_INTERVAL_S),
        "alert_retry_s": "0.5",
    }


# Three server starts (two of two processes), each waited for up to HUNG_SERVER_S: the
# suite's default 120 s ended it at 119 s with three workers on two busy cores. Only a
# hang guard, as that wait is.
@pytest.mark.timeout(3 * HUNG_SERVER_S)
def test_an_alert_is_posted_once_per_event_and_again_after_it_clears_and_fires(
    database: Database, database_url: str, receiver: Receiver, tmp_path: Path
) -> None:
    settings = _settings(tmp_path, receiver)
    with serving(database_url, **settings) as base:
        _store(database, "pfpf", 0)  # 2 of the last 4 passed first time: 50 % < 75 %
        receiver.wait("alert", lambda: receiver.received)
        _rounds_later(base)
        _store(database, "f", 10)  # still below: the same event
        shown = _rounds_later(base)
    (posted,) = receiver.received
    assert posted["rule"] == "yield"
    assert posted["scope"] == "st1"
    assert posted["evidence"]["passed"] == 2
    assert posted["evidence"]["failed"] == ["PT000003", "PT000001"]
    assert [a["event_key"] for a in shown["alerts"]] == [posted["event_key"]]
    assert shown["alerts"][0]["delivered_at"] is not None
    # Restarted, as two server processes: the event is stored and delivered already.
    with serving(database_url, workers=2, **settings) as base:
        _rounds_later(base, 2, processes=2)
        page = local_get(f"{base}/alerts").text
        link = page.split('<a class="runs" href="', 1)[1].split('"', 1)[0]
        report = local_get(f"{base}{link.replace('&amp;', '&')}").text
        assert "PT000001" in report
        assert 'href="/alerts"' in local_get(f"{base}/").text  # every page's navigation
        assert len(receiver.received) == 1
        _store(database, "pppp", 20)  # the last 4 all passed: the alert clears
        for _ in range(int(PATIENCE_S / ALERT_INTERVAL_S)):
            if _alerts(base)["alerts"][0]["cleared_at"] is not None:
                break
            threading.Event().wait(ALERT_INTERVAL_S)
        assert _alerts(base)["alerts"][0]["cleared_at"] is not None
        _store(database, "ff", 30)  # below again: a new event
        receiver.wait("second alert", lambda: len(receiver.received) >= 2)
        _rounds_later(base, 2, processes=2)
    assert len(receiver.received) == 2
    assert receiver.received[1]["event_key"] != posted["event_key"]
    assert receiver.received[1]["evidence"]["failed"] == ["PT000031", "PT000030"]


def test_an_alert_the_webhook_refused_is_posted_again_once_it_is_back(
    database: Database, database_url: str, receiver: Receiver, tmp_path: Path
) -> None:
    receiver.down = True
    with serving(database_url, **_settings(tmp_path, receiver)) as base:
        _store(database, "ffpp", 0)
        receiver.wait("attempt", lambda: receiver.refused >= 2)
        (waiting,) = _alerts(base)["alerts"]
        assert waiting["delivered_at"] is None
        assert waiting["attempts"] >= 2
        with receiver.changed:
            receiver.down = False
        receiver.wait("alert", lambda: receiver.received)
        _rounds_later(base, 3)
        (delivered,) = _alerts(base)["alerts"]
    assert len(receiver.received) == 1
    assert receiver.received[0]["event_key"] == delivered["event_key"]
    assert delivered["delivered_at"] is not None


def test_a_silent_station_fires_once_and_clears_when_it_runs_again(
    database: Database, database_url: str, receiver: Receiver, tmp_path: Path
) -> None:
    rules = 'webhook = "{webhook}"\n[[silent]]\nstation = "st2"\nminutes = 60\n'
    settings = _settings(tmp_path, receiver, rules)
    with serving(database_url, **settings) as base:
        with database.session() as session, session.begin():
            # Its last run weeks ago (the history's T0); st1 ran since, st2 did not.
            repository = RunRepository(session)
            repository.submit(make_record(serial="PT000001", station_id="st2"))
            repository.submit(
                make_record(serial="PT000002", station_id="st1", started_at=datetime.now(UTC))
            )
        receiver.wait("alert", lambda: receiver.received)
        (posted,) = receiver.received
        assert (posted["rule"], posted["scope"]) == ("silent", "st2")
        assert posted["evidence"]["last_serial"] == "PT000001"
        assert posted["evidence"]["silent_minutes"] > 60
        with database.session() as session, session.begin():
            RunRepository(session).submit(
                make_record(serial="PT000003", station_id="st2", started_at=datetime.now(UTC))
            )
        shown = _rounds_later(base)
        assert shown["alerts"][0]["cleared_at"] is not None
        page = local_get(f"{base}/alerts").text
        assert 'last run: <a class="serial" href="/units/PT000001">' in page
    assert len(receiver.received) == 1


def test_a_western_electric_signal_on_the_latest_run_fires_once(
    database: Database, database_url: str, receiver: Receiver, tmp_path: Path
) -> None:
    rules = (
        'webhook = "{webhook}"\n[[western_electric]]\nparameter = "offset_x"\n'
        'station = "st1"\nruns = 20\n'
    )
    settings = _settings(tmp_path, receiver, rules)

    in_control = [2079.0, 2083.0] * 6  # alternating about the centre, within 1σ
    with serving(database_url, **settings) as base:
        _store_offsets(database, in_control, 0, "st1")
        assert _rounds_later(base)["alerts"] == []
        _store_offsets(database, [2100.0], 20, "st1")
        receiver.wait("alert", lambda: receiver.received)
        _store_offsets(database, [2081.0], 30, "st1")  # back in control: the alert clears
        shown = _rounds_later(base)
    # By hand: the chart of the 13 runs up to the spike, x̄ and σ = MR̄/d₂ (d₂ = 1.128).
    values = np.array([*in_control, 2100.0])
    sigma = np.abs(np.diff(values)).mean() / 1.128
    assert values[-1] - values.mean() > 3 * sigma  # rule 1
    (posted,) = receiver.received
    assert (posted["rule"], posted["scope"]) == ("western_electric", "st1")
    assert posted["evidence"]["serial"] == "PT000020"
    assert 1 in posted["evidence"]["rules"]
    assert np.isclose(posted["evidence"]["sigma"], sigma)
    assert shown["alerts"][0]["cleared_at"] is not None


def test_a_cpk_below_its_target_fires_once_and_clears_when_capable_again(
    database: Database, database_url: str, receiver: Receiver, tmp_path: Path
) -> None:
    rules = 'webhook = "{webhook}"\n[[cpk]]\nparameter = "offset_x"\nruns = 10\ntarget = 1.33\n'
    settings = _settings(tmp_path, receiver, rules)

    capable = [2046.0, 2050.0] * 5
    spread = [1900.0, 2200.0] * 5
    with serving(database_url, **settings) as base:
        _store_offsets(database, capable, 0)
        assert _rounds_later(base)["alerts"] == []
        _store_offsets(database, spread, 10)
        receiver.wait("alert", lambda: receiver.received)
        _store_offsets(database, capable, 20)  # the last 10 capable again: the alert clears
        shown = _rounds_later(base)
    # By hand, against the shipped production limits of offsets, 1841 … 2255 counts.
    values = np.array(spread)
    mean, sd = values.mean(), values.std(ddof=1)
    expected = min(2255.0 - mean, mean - 1841.0) / (3 * sd)
    assert expected < 1.33
    (posted,) = receiver.received
    assert (posted["rule"], posted["scope"]) == ("cpk", "line")
    assert np.isclose(posted["evidence"]["cpk"], expected)
    assert (posted["evidence"]["lower"], posted["evidence"]["upper"]) == (1841.0, 2255.0)
    assert shown["alerts"][0]["cleared_at"] is not None
    assert len(receiver.received) == 1


def test_a_station_outbox_backlog_fires_once_and_clears_when_it_drains(
    database_url: str, station_key: str, receiver: Receiver, tmp_path: Path
) -> None:
    settings = _settings(
        tmp_path, receiver, 'webhook = "{webhook}"\n[[outbox]]\nqueued = 3\nhours = 1\n'
    )
    # Three runs the store failed on wait for their retry (the backoff's clock stands
    # still until the test moves it), the oldest for two hours; one file was refused.
    clock = [0.0]
    outbox = Outbox(tmp_path / "outbox", backoff=RecordBackoff(lambda: clock[0]))
    for i in range(3):
        record = make_record(serial=f"PT00001{i}", station_id=STATION)
        outbox.put(record)
        outbox.backoff.failed(f"{record.run_id}.json", "the store failed on it")
    two_hours_ago = datetime.now(UTC).timestamp() - 2 * 3600
    os.utime(outbox.pending()[0], (two_hours_ago, two_hours_ago))
    outbox.refused_dir.mkdir()
    refused = outbox.refused_dir / f"{make_record().run_id}.json"
    refused.write_text("{}")
    outbox.put(make_record(serial="PT000020", station_id=STATION))
    with serving(database_url, **settings) as base, HttpStore(base, station_key) as store:
        sent = outbox.sync(store)
        assert (sent.stored, sent.pending) == (1, 3)
        receiver.wait("alert", lambda: receiver.received)
        (posted,) = receiver.received
        assert (posted["rule"], posted["scope"]) == ("outbox", STATION)
        evidence = posted["evidence"]
        assert (evidence["queued"], evidence["set_aside"]) == (3, 1)
        assert evidence["oldest_s"] >= 2 * 3600
        page = local_get(f"{base}/alerts").text
        assert '<span class="outbox">3 runs queued, the oldest waiting 2' in page
        assert "1 file set aside (reported " in page
        # The operator dealt with the refused file; the runs' retry comes: all stored.
        refused.unlink()
        clock[0] += 3600
        sent = outbox.sync(store)
        assert (sent.stored, sent.pending) == (3, 0)
        shown = _rounds_later(base)
        assert shown["alerts"][0]["cleared_at"] is not None
    assert len(receiver.received) == 1


def test_a_run_with_a_bad_outbox_header_or_none_is_stored_without_a_report(
    database: Database, live_url: str, station_key: str
) -> None:
    # The header is monitoring: a good run is never refused for it (the station would
    # set the run aside as refused).
    bad = make_record(serial="PT000001", station_id=STATION)
    older = make_record(serial="PT000002", station_id=STATION)
    base = live_url  # no alert rules: the worker's shared server
    with HttpStore(base, station_key) as store:
        for header in ("queued=-1; oldest_s=0; set_aside=0", "queued=1; oldest_s=5; set_aside=0;"):
            answer = httpx.post(
                f"{base}/api/v1/runs",
                content=bad.model_dump_json(),
                headers={
                    "Authorization": f"Bearer {station_key}",
                    "Content-Type": "application/json",
                    OUTBOX_HEADER: header,
                },
                timeout=HUNG_SERVER_S,
            )
            assert answer.status_code in (200, 201), answer.text
        stored = local_get(f"{base}/api/v1/runs/{bad.run_id}")
        assert stored.status_code == 200
        assert store.submit(older).created  # a station that does not report its outbox
    with database.session() as session:
        assert session.scalars(select(StationOutbox)).all() == []
        assert RunRepository(session).get(older.run_id) is not None


def test_a_slow_webhook_gets_each_alert_once_from_two_server_processes(
    database: Database, database_url: str, receiver: Receiver, tmp_path: Path
) -> None:
    # The webhook answers after 2 s, four retry intervals: the process posting an alert
    # holds it until the answer, so the other never posts it too.
    receiver.delay_s = 2.0
    with serving(database_url, workers=2, **_settings(tmp_path, receiver)) as base:
        _store(database, "pfpf", 0)
        receiver.wait("alert", lambda: receiver.received)
        _rounds_later(base, 3, processes=2)
    assert len(receiver.received) == 1


@pytest.mark.parametrize(
    ("content", "named"),
    [
        (None, "No such file or directory"),
        ('webhook = "nope"\n', "webhook: Input should be a valid URL"),
        ('webhook = "http://h/x"\n[[yield]]\nunits = 0\ngoal = 0.9\n', "yield.0.units"),
        ("webhook = [", "not valid TOML"),
    ],
)
def test_an_unusable_alerts_file_stops_the_server_with_one_line(
    run_cli: CliRunner, tmp_path: Path, content: str | None, named: str
) -> None:
    rules = tmp_path / "alerts.toml"
    if content is not None:
        rules.write_text(content)
    clean = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    env = {**clean, "CALSTATION_DATA_DIR": str(tmp_path), "CALSTATION_ALERTS_FILE": str(rules)}
    result = run_cli("serve", "--port", "1", env=env)
    assert result.returncode == 2, result.stderr
    assert result.stderr.startswith(f"calstation: error: CALSTATION_ALERTS_FILE: {rules}: ")
    assert named in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
