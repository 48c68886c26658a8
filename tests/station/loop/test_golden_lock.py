"""The golden unit: its comparison, its schedule, and the lock kept in real files."""

import json
from datetime import UTC, datetime, time, timedelta
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.domain.quality.golden import GoldenUnit, disagreements, due
from station.domain.record.records import RunRecord
from station.loop.golden_lock import GoldenLock
from station.loop.shift_checks import ShiftChecks, unlock_usage
from tests.conftest import examples
from tests.db.records import make_record

OFFSET = (2081.9, 2041.2, 1960.5)
SENSITIVITY = (813.95, 815.66, 820.17)
GOLDEN = GoldenUnit(
    serial="GU-001",
    offset_counts=OFFSET,
    sensitivity_counts_per_g=SENSITIVITY,
    gyro_bias_dps=(0.01, -0.02, 0.005),
)
T0 = datetime(2026, 11, 2, 8, 0, tzinfo=UTC)


def golden_run(offset: tuple[float, float, float] = OFFSET, **kw: object) -> RunRecord:
    record = make_record(serial="GU-001", offset=offset, sensitivity=SENSITIVITY, **kw)
    return record.model_copy(update={"purpose": "golden", "disposition": None})


def test_a_run_within_tolerance_agrees_and_one_beyond_names_what_disagrees() -> None:
    assert disagreements(GOLDEN, golden_run((2085.0, 2038.0, 1963.0))) == []
    off = golden_run((2081.9 + 13.4, 2041.2, 1960.5))
    assert disagreements(GOLDEN, off) == ["offset x 2095.3 vs reference 2081.9 ± 5"]
    failed = make_record(serial="GU-001", verdict="fail", coefficients=None, quality=None)
    assert disagreements(GOLDEN, failed) == ["failed (sensitivity_out_of_range)"]
    biased = GOLDEN.model_copy(update={"gyro_bias_dps": (0.5, -0.02, 0.005)})
    assert disagreements(biased, golden_run()) == ["gyro bias x 0.01 vs reference 0.5 ± 0.2"]


def test_the_golden_unit_is_due_after_its_period_and_at_each_shift_start() -> None:
    assert due(GOLDEN, None, T0)
    assert not due(GOLDEN, T0, T0 + timedelta(hours=7, minutes=59))
    assert due(GOLDEN, T0, T0 + timedelta(hours=8))
    local = T0.astimezone()
    start = (local + timedelta(hours=2)).time().replace(second=0, microsecond=0)
    shifts = GOLDEN.model_copy(update={"shift_starts": (start,)})
    assert not due(shifts, T0, T0 + timedelta(hours=1))
    assert due(shifts, T0, T0 + timedelta(hours=2, minutes=1))


@given(
    last=st.integers(0, 7 * 24 * 60),
    gap=st.integers(0, 3 * 24 * 60),
    later=st.integers(0, 24 * 60),
    starts=st.lists(st.integers(0, 24 * 60 - 1), max_size=3),
)
@settings(max_examples=examples(100), deadline=None)
def test_once_due_it_stays_due_until_checked(
    last: int, gap: int, later: int, starts: list[int]
) -> None:
    unit = GOLDEN.model_copy(update={"shift_starts": tuple(time(m // 60, m % 60) for m in starts)})
    checked = T0 + timedelta(minutes=last)
    now = checked + timedelta(minutes=gap)
    if due(unit, checked, now):
        assert due(unit, checked, now + timedelta(minutes=later))
    assert not due(unit, checked, checked)


def test_a_disagreeing_golden_unit_locks_the_station_across_a_restart(tmp_path: Path) -> None:
    checks = ShiftChecks(GOLDEN, tmp_path, "st-1")
    assert checks.at_scan("PT000001").said is not None  # due: never checked
    assert checks.at_scan("GU-001").golden
    said = checks.at_verdict(golden_run((2081.9 + 13.4, 2041.2, 1960.5)))
    expected = (
        "LOCKED: golden unit GU-001 offset x 2095.3 vs reference 2081.9 ± 5: call a supervisor"
    )
    assert said == expected
    # A new station process reads the lock from its data directory.
    again = ShiftChecks(GOLDEN, tmp_path, "st-1")
    assert again.lines() == [expected]
    assert again.at_scan("PT000001").said == expected
    assert again.at_scan("GU-001").said == expected
    assert again.at_scan("unlock j.smith").said == unlock_usage()
    unlocked = again.at_scan("unlock j.smith jig reseated, reference checked")
    assert unlocked.said == (
        "UNLOCKED by j.smith: jig reseated, reference checked (recorded in audit-st-1.jsonl)"
    )
    assert again.at_scan("PT000001") == again.at_scan("PT000002")  # both go on
    assert again.at_scan("PT000001").said is None
    events = [json.loads(line) for line in (tmp_path / "audit-st-1.jsonl").read_text().splitlines()]
    assert [e["event"] for e in events] == ["lock", "unlock"]
    assert events[1]["supervisor"] == "j.smith"
    assert events[1]["reason"] == "jig reseated, reference checked"
    assert events[1]["was"] == expected


def test_an_agreeing_golden_unit_lets_production_go_on(tmp_path: Path) -> None:
    checks = ShiftChecks(GOLDEN, tmp_path, "st-1")
    said = checks.at_verdict(golden_run(started_at=datetime.now(UTC)))
    assert said == "GOLDEN OK: golden unit GU-001 agrees with its reference: go on"
    assert checks.lines() == []
    assert checks.at_scan("PT000001").said is None


def test_an_unreadable_golden_state_locks_the_station(tmp_path: Path) -> None:
    (tmp_path / "golden-st-1.json").write_bytes(b"\xff\xfe torn")
    lock = GoldenLock(GOLDEN, tmp_path, "st-1")
    line = lock.line()
    assert line is not None
    assert line.startswith("LOCKED: golden state golden-st-1.json unreadable")
    assert lock.unlock("j.smith", "file restored").startswith("UNLOCKED by j.smith")
    assert lock.line() is None


def test_a_station_without_a_golden_unit_never_asks_for_one(tmp_path: Path) -> None:
    checks = ShiftChecks(None, tmp_path, "st-1")
    assert checks.lines() == []
    assert checks.at_scan("PT000001").said is None
    assert not checks.at_scan("GU-001").golden


@pytest.mark.parametrize("drift", [0.0, 40.0], ids=["steady", "drifting"])
def test_the_drift_line_follows_the_stations_own_passed_units(tmp_path: Path, drift: float) -> None:
    rng = np.random.default_rng(9)
    checks = ShiftChecks(GOLDEN, tmp_path, "st-1")
    said = None
    for k in range(20):
        offset = 2048 + rng.uniform(-150, 150, 3)
        offset[1] += drift * k
        record = make_record(serial=f"PT{k:06d}", offset=tuple(offset))
        said = checks.at_verdict(record)
    restarted = ShiftChecks(None, tmp_path, "st-1")
    if drift:
        assert said is not None
        assert said.startswith("DRIFT: offset y rising over the last 20 units")
        assert restarted.lines() == [said]
    else:
        assert said is None
        assert restarted.lines() == []
