"""The golden unit through a real ``calstation run`` process: due, lock, restart, unlock.

A real station process in a pty, the virtual putter (the golden unit) on its port, the
embedded SQLite database, the lock and the audit file in the station's data directory.
"""

import json
from pathlib import Path

import pexpect
import pytest

from tests.station.loop.test_station_terminal import Station
from tests.terminal import hang_guard

GOLDEN = "PT900001"


@hang_guard
def test_a_disagreeing_golden_unit_locks_the_station_until_a_supervisor_unlocks_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    station = Station(tmp_path, serial=GOLDEN)
    truth = station.putter.truth
    # The reference says offset x is 13.4 counts above what the unit really has.
    reference = {
        "serial": GOLDEN,
        "offset_counts": [truth.offset_counts[0] + 13.4, *truth.offset_counts[1:]],
        "sensitivity_counts_per_g": truth.sensitivity_counts_per_g.tolist(),
    }
    monkeypatch.setenv("CALSTATION_GOLDEN", json.dumps(reference))
    try:
        child = station.start()
        child.expect(f"GOLDEN UNIT due: scan golden unit {GOLDEN}")
        station.scan("PT000001")
        child.expect(f"GOLDEN UNIT due: scan golden unit {GOLDEN} before the next unit")
        station.scan()
        assert station.follow() == "PASS"
        child.expect(
            rf"LOCKED: golden unit {GOLDEN} offset x [\d.]+ vs reference "
            rf"{reference['offset_counts'][0]:.1f} ± 5: call a supervisor"
        )
        station.scan("PT000001")
        child.expect("LOCKED: golden unit")
        # The lock survives a restart of the station.
        child.sendeof()
        child.expect(pexpect.EOF)
        child = station.start()
        child.expect(f"LOCKED: golden unit {GOLDEN} offset x")
        station.scan("unlock j.smith reference re-measured on the lab bench")
        child.expect("UNLOCKED by j.smith: reference re-measured on the lab bench")
        # Production goes on: the scan reaches the port (where the golden unit still is).
        station.scan("PT000001")
        child.expect("serial number mismatch")
    finally:
        station.close()
    rows = station.rows("select serial, verdict, purpose, disposition from runs")
    assert rows == [(GOLDEN, "pass", "golden", None)]
    audit = tmp_path / "data" / "audit-st-1.jsonl"
    events = [json.loads(line) for line in audit.read_text(encoding="utf-8").splitlines()]
    assert [e["event"] for e in events] == ["lock", "unlock"]
    assert events[1]["supervisor"] == "j.smith"
    assert events[1]["reason"] == "reference re-measured on the lab bench"
