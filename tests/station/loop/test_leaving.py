"""Leaving the station and coming back, as an operator does it on a real terminal: Ctrl-C
mid-unit says, in one line in the operator's language, that the unit's journal was kept
and how it resumes; a label queued for the next unit survives a restart."""

import signal
from collections.abc import Iterator
from pathlib import Path

import pexpect
import pytest

from tests.station.loop.test_station_terminal import Station
from tests.terminal import hang_guard

pytestmark = hang_guard

#: What Ctrl-C mid-unit says, by language, and the pose the unit is at (the pose words
#: the test follows are English: in the others it stops at the first pose).
KEPT = {
    "en": (
        3,
        "stopped (Ctrl-C): the journal of unit PT000042 is kept at pose 3 of 7: "
        "the station offers to resume it when it starts again",
    ),
    "ko": (
        1,
        "중지됨 (Ctrl-C): 유닛 PT000042의 작업 기록을 자세 1/7에 보관했습니다: "
        "스테이션을 다시 시작하면 이어서 할지 묻습니다",
    ),
    "zh": (
        1,
        "已停止（Ctrl-C）：产品 PT000042 的作业记录已保存在姿态 1/7：工位重新启动时会询问是否继续",
    ),
}


@pytest.fixture
def station(tmp_path: Path) -> Iterator[Station]:
    s = Station(tmp_path)
    yield s
    s.close()


@pytest.mark.parametrize("language", ["en", "ko", "zh"])
def test_ctrl_c_mid_unit_says_the_journal_is_kept_and_the_unit_resumes(
    station: Station, language: str
) -> None:
    number, kept = KEPT[language]
    child = station.start(prompt=False, extra=("--language", language))
    child.expect("█")  # the serial prompt's cursor
    station.scan()
    if language == "en":
        station.follow(until_pose=number)
    else:
        child.expect(["자세 1/7", "姿态 1/7"])
    child.kill(signal.SIGINT)
    child.expect(pexpect.EOF)
    said = " ".join(child.before.replace("\r", "").split())
    assert " ".join(kept.split()) in said, said[-400:]
    assert "Traceback" not in said
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
