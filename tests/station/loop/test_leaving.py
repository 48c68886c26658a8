"""Leaving the station and coming back, as an operator does it on a real terminal: Ctrl-C
mid-unit says, in one line in the operator's language, that the unit's journal was kept
and how it resumes; a label queued for the next unit survives a restart, at the one-port
station and at a fixture."""

import os
import re
import signal
import sys
from collections.abc import Iterator
from pathlib import Path

import pexpect
import pytest

from station.simulator.putter import VirtualPutter
from tests.conftest import REPO_ROOT
from tests.station.loop.test_station_terminal import Station
from tests.terminal import hang_guard, spawn

pytestmark = hang_guard

#: What Ctrl-C mid-unit says, by language, of unit ``{serial}`` at pose ``{number}``.
STOPPED = {
    "en": "stopped (Ctrl-C): the journal of unit {serial} is kept at pose {number} of 7: "
    "the station offers to resume it when it starts again",
    "ko": "중지됨 (Ctrl-C): 유닛 {serial}의 작업 기록을 자세 {number}/7에 보관했습니다: "
    "스테이션을 다시 시작하면 이어서 할지 묻습니다",
    "zh": "已停止（Ctrl-C）：产品 {serial} 的作业记录已保存在姿态 {number}/7："
    "工位重新启动时会询问是否继续",
}
#: The pose the unit is at when Ctrl-C comes (the pose words the test follows are
#: English: in the others it stops at the first pose).
STOPPED_AT = {"en": 3, "ko": 1, "zh": 1}
#: A pose asked for on the unit's screen, in each language.
POSE_SHOWN = {"en": "pose 1 of 7", "ko": "자세 1/7", "zh": "姿态 1/7"}


def said(child: pexpect.spawn) -> str:
    """What the stopped process showed, its lines and the terminal's wrapping joined."""
    return " ".join(child.before.replace("\r", "").split())


@pytest.fixture
def station(tmp_path: Path) -> Iterator[Station]:
    s = Station(tmp_path)
    yield s
    s.close()


@pytest.mark.parametrize("language", ["en", "ko", "zh"])
def test_ctrl_c_mid_unit_says_the_journal_is_kept_and_the_unit_resumes(
    station: Station, language: str
) -> None:
    number = STOPPED_AT[language]
    child = station.start(prompt=False, extra=("--language", language))
    child.expect("█")  # the serial prompt's cursor
    station.scan()
    if language == "en":
        station.follow(until_pose=number)
    else:
        child.expect(POSE_SHOWN[language])
    child.kill(signal.SIGINT)
    child.expect(pexpect.EOF)
    shown = said(child)
    assert STOPPED[language].format(serial="PT000042", number=number) in shown, shown[-400:]
    assert "Traceback" not in shown
    child.wait()
    assert child.exitstatus == 130
    assert (station.tmp / "data" / "journal-st-1.json").is_file()
    child = station.start(prompt=False)
    child.expect(f"Unit PT000042 was interrupted at pose {number} of 7")


def test_a_label_queued_for_the_next_unit_survives_a_restart(station: Station) -> None:
    child = station.start()
    station.scan()
    station.follow(until_pose=2)
    child.send("PT000043\r")  # the next unit's label, scanned during this one
    child.expect("next unit PT000043 scanned")
    child.kill(signal.SIGINT)
    child.expect(pexpect.EOF)
    child.wait()
    child = station.start(prompt=False)
    child.expect("Unit PT000042 was interrupted at pose 2 of 7")
    child.send("n")  # discard it: the serial prompt comes, the queued label with it
    child.expect(r"Enter: PT000043, scanned during the last unit")
    child.kill(signal.SIGINT)
    child.expect(pexpect.EOF)
    child.wait()
    child = station.start(prompt=False)
    child.expect(r"Enter: PT000043, scanned during the last unit")


class FixtureStation:
    """A ``calstation run`` process of a two-slot fixture in a pty, and the virtual units
    in its slots' ptys. The units' clock runs at a tenth of real time: a pose the fixture
    waits for times out (30 s of the units' time) long after the test is done with it."""

    def __init__(self, tmp: Path) -> None:
        self.tmp = tmp
        self.ports = [tmp / "slot1", tmp / "slot2"]
        self.putters: dict[int, VirtualPutter] = {}
        self.child: pexpect.spawn | None = None

    def plug(self, slot: int, serial: str) -> None:
        """Put the unit ``serial`` in ``slot`` (the unit there before taken out)."""
        if slot in self.putters:
            self.putters.pop(slot).close()
        putter = VirtualPutter(seed=slot, serial=serial, speed=0.1)
        putter.serve_pty(self.ports[slot - 1])
        self.putters[slot] = putter

    def start(self) -> pexpect.spawn:
        env = {
            **os.environ,
            "PYTHONPATH": str(REPO_ROOT),
            "CALSTATION_DATA_DIR": str(self.tmp / "data"),
            "CALSTATION_DATABASE_URL": f"sqlite:///{self.tmp / 'results.sqlite3'}",
            "TERM": "xterm-256color",
            "COLUMNS": "140",
            "LINES": "60",
        }
        ports = [arg for port in self.ports for arg in ("--port", str(port))]
        argv = [sys.executable, "-m", "station", "run", *ports, "--station", "st-1"]
        self.child = spawn([*argv, "--operator", "op-7"], env=env, cwd=REPO_ROOT)
        return self.child

    def stop(self, sig: signal.Signals) -> str:
        """Stop the station with ``sig``; what it showed last."""
        assert self.child is not None
        self.child.kill(sig)
        self.child.expect(pexpect.EOF)
        self.child.wait()
        return " ".join(self.child.before.replace("\r", "").split())

    def close(self) -> None:
        if self.child is not None and self.child.isalive():
            self.child.kill(signal.SIGKILL)
            self.child.wait()
        for putter in self.putters.values():
            putter.close()


@pytest.fixture
def fixture_station(tmp_path: Path) -> Iterator[FixtureStation]:
    s = FixtureStation(tmp_path)
    yield s
    s.close()


def test_labels_scanned_ahead_at_a_fixture_survive_a_restart(
    fixture_station: FixtureStation,
) -> None:
    station = fixture_station
    station.plug(1, "PT000501")
    station.plug(2, "PT000502")
    child = station.start()
    child.expect("Scan the unit in slot 1")
    child.send("PT000501\r")
    child.expect("Scan the unit in slot 2")
    child.send("PT000502\r")
    child.expect("scan the next units' labels now")  # the cycle runs: scan ahead
    child.send("PT000601\r")
    child.expect("slot 1 ← PT000601")
    child.send("nope\r")  # refused: it never takes a slot's place
    child.expect("'nope' is not a serial number")
    child.send("PT000602\r")
    child.expect("slot 1 ← PT000601, slot 2 ← PT000602")
    station.stop(signal.SIGKILL)  # a crash: nothing said, nothing saved on the way out

    child = station.start()
    child.expect(r"Resume them\? press y")
    child.send("n")  # the cycle's units are discarded; the labels scanned ahead stay
    child.expect("Put PT000601 in slot 1, then Enter")
    child.expect("PT000602 scanned ahead: Enter at its scan")
    child.send("PT000777\r")  # a unit that is not in slot 1: the label offered stays
    child.expect("wrong unit in slot 1: it reports PT000501")
    child.send("nope\r")
    child.expect("'nope' is not a serial number")
    child.expect("Put PT000601 in slot 1, then Enter")
    assert "no unit was in progress" in station.stop(signal.SIGINT)
    assert child.exitstatus == 130

    station.plug(1, "PT000601")  # the units laid out for the slots put in
    station.plug(2, "PT000602")
    child = station.start()
    child.expect("scanned ahead before the station stopped: slot 1 ← PT000601, slot 2 ← PT000602")
    child.expect("Put PT000601 in slot 1, then Enter")
    child.send("\r")
    child.expect("Put PT000602 in slot 2, then Enter")
    child.send("\r")
    child.expect(r"fixture loaded \(slots 1, 2\)")
    data = station.tmp / "data"
    assert not list(data.glob("next-unit-*"))  # loaded: no longer queued
    said = station.stop(signal.SIGINT)
    assert "the journals of units PT000601, PT000602 are kept" in said, said[-400:]


@pytest.mark.parametrize("language", ["en", "ko", "zh"])
def test_ctrl_c_in_the_demo_says_what_run_says_and_exits_130(tmp_path: Path, language: str) -> None:
    env = {
        **os.environ,
        "PYTHONPATH": str(REPO_ROOT),
        "CALSTATION_DATA_DIR": str(tmp_path / "data"),
        "TERM": "xterm-256color",
        "COLUMNS": "140",
        "LINES": "60",
    }
    env.pop("CALSTATION_DATABASE_URL", None)
    argv = [sys.executable, "-m", "station", "demo", "--units", "2", "--language", language]
    child = spawn(argv, env=env, cwd=REPO_ROOT)
    child.expect(POSE_SHOWN[language])  # the demo's first unit, PT001001, at its poses
    child.kill(signal.SIGINT)
    child.expect(pexpect.EOF)
    shown = said(child)
    kept = re.escape(STOPPED[language].format(serial="PT001001", number="N")).replace("N", r"\d")
    assert re.search(kept, shown), shown[-400:]
    assert "Traceback" not in shown
    child.wait()
    assert child.exitstatus == 130
    assert (tmp_path / "data" / "journal-demo-station.json").is_file()
