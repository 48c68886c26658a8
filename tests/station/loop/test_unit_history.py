"""A unit's history at the station: from both stores and the outbox; what the scan says,
where the verdict sends the unit; port errors in the operator's words."""

from datetime import timedelta
from pathlib import Path
from typing import Any

import pytest

from db import Database
from station.device import PutterDriver
from station.domain.errors import CalstationError
from station.domain.record.records import HoldReview, RunRecord
from station.domain.record.unit_state import disposition
from station.loop.unit_history import ScanAction, UnitHistory
from station.results.outbox import Outbox
from station.results.storage import DatabaseStore, HttpStore, StoreUnavailableError
from station.run.operator_text import port_problem
from tests.db.records import T0, make_record
from tests.servers import free_port

ABORT: dict[str, Any] = {
    "verdict": "fail",
    "failures": [{"code": "aborted", "message": "aborted by the operator"}],
    "coefficients": None,
    "quality": None,
}


def _fail(code: str, minutes: int = 0) -> RunRecord:
    return make_record(
        verdict="fail",
        started_at=T0 + timedelta(minutes=minutes),
        failures=[{"code": code, "message": "out of limits"}],
    )


@pytest.mark.parametrize(
    ("earlier", "run", "expected"),
    [
        ([], make_record(), "ship"),
        ([], _fail("offset"), "retest"),
        ([_fail("offset", -20)], _fail("offset"), "retest"),
        ([_fail("offset", -20), _fail("offset", -10)], _fail("offset"), "rework"),
        ([], _fail("saturated"), "rework"),
        ([], _fail("writeback"), "rework"),
        ([make_record(started_at=T0 - timedelta(minutes=5))], make_record(**ABORT), "ship"),
        ([_fail("offset", -5)], make_record(**ABORT), "retest"),
        (
            [_fail("offset", -9), _fail("offset", -5), _fail("pose_noise", -2)],
            make_record(**ABORT),
            "rework",
        ),
    ],
)
def test_disposition(earlier: list[RunRecord], run: RunRecord, expected: str) -> None:
    assert disposition(run, earlier, retest_limit=3) == expected


def test_the_database_store_gives_the_history_and_the_outbox_adds_what_waits(
    database: Database, tmp_path: Path
) -> None:
    stored, waiting = (
        make_record(serial="PT000123"),
        make_record(serial="PT000123", started_at=T0 + timedelta(hours=1), **ABORT),
    )
    outbox = Outbox(tmp_path / "outbox")
    outbox.put(waiting)
    outbox.put(make_record(serial="PT000999"))
    (tmp_path / "outbox" / "broken.json").write_text('{"serial": "PT000123", ')
    with DatabaseStore(database=database) as store:
        store.submit(stored)
        history = UnitHistory.gather("PT000123", store, outbox.pending())
    assert [r.run_id for r in history.runs] == [stored.run_id, waiting.run_id]
    assert history.unavailable is None
    decision = history.at_scan(3)
    assert decision.action is ScanAction.CONFIRM
    assert decision.text is not None
    assert decision.text.startswith("PT000123 passed at ")
    assert decision.text.endswith(f" on {stored.station_id}: calibrate again? y/n")


def test_the_http_store_gives_the_history_over_the_units_route(
    live_url: str, database: Database, station_key: str
) -> None:
    record = make_record()
    with HttpStore(live_url, station_key) as store:
        store.submit(record)
        assert [r.run_id for r in store.history(record.serial)] == [record.run_id]
        assert store.history("PT404404") == []


def test_an_unreachable_store_leaves_the_history_unavailable_and_the_unit_goes_on(
    tmp_path: Path,
) -> None:
    with HttpStore(f"http://127.0.0.1:{free_port()}", "csk_x", timeout=2) as store:
        with pytest.raises(StoreUnavailableError):
            store.history("PT000123")
        history = UnitHistory.gather("PT000123", store, [])
    decision = history.at_scan(3)
    assert decision.action is ScanAction.START
    assert decision.note is not None
    assert decision.note.startswith("history of PT000123 unavailable (")


def test_a_missing_port_is_said_in_words_naming_it_once(tmp_path: Path) -> None:
    port = tmp_path / "ttyUSB9"
    with pytest.raises(CalstationError) as caught:
        PutterDriver.open(str(port))
    words = port_problem(caught.value)
    assert words == "no such port: is the unit's cable plugged in?"
    assert str(port) not in words


def _review(decision: str, minutes: int, run: RunRecord) -> HoldReview:
    return HoldReview(
        serial=run.serial,
        run_id=run.run_id,
        reviewed_at=T0 + timedelta(minutes=minutes),
        reviewer="qe-ana",
        root_cause="cracked joint",
        repair_action="reflowed",
        decision=decision,  # type: ignore[arg-type]
    )


def test_a_release_counts_attempts_afresh_and_a_scrap_ends_the_unit() -> None:
    runs = tuple(_fail("offset", m) for m in (0, 10, 20))  # the third used up the limit
    held = runs[-1].model_copy(update={"disposition": "rework"})
    history = UnitHistory(held.serial, (*runs[:2], held))
    assert history.at_scan(3).action is ScanAction.REFUSE
    released = UnitHistory(held.serial, (*runs[:2], held), reviews=(_review("retest", 30, held),))
    assert released.counted == ()
    assert released.at_scan(3).action is ScanAction.START
    after = _fail("offset", 40).model_copy(update={"disposition": "retest"})
    again = UnitHistory(
        held.serial, (*runs[:2], held, after), reviews=(_review("retest", 30, held),)
    )
    assert again.counted == (after,)
    assert again.at_scan(3).action is ScanAction.START  # one attempt since the release
    scrapped = UnitHistory(held.serial, (*runs[:2], held), reviews=(_review("scrap", 30, held),))
    decision = scrapped.at_scan(3)
    assert decision.action is ScanAction.REFUSE
    assert decision.text is not None
    assert "was scrapped by qe-ana" in decision.text


def test_a_broken_unit_is_refused_before_its_attempts_are_used() -> None:
    broken = _fail("saturated").model_copy(update={"disposition": "rework"})
    decision = UnitHistory(broken.serial, (broken,)).at_scan(3)
    assert decision.action is ScanAction.REFUSE
    assert decision.text is not None
    assert "sent to rework" in decision.text
    assert "(saturated)" in decision.text
