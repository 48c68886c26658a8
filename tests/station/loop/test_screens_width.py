"""The screens in Korean and Chinese keep their layout in 80 columns: every line fits in
80 terminal cells (a Hangul or Han character takes two), and the operator reads their
own language."""

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from rich.cells import cell_len
from rich.console import Console, Group, RenderableType

from station.domain.i18n import set_language
from station.domain.limits import Bounds, check, load_profile
from station.domain.orientation import Sensed
from station.domain.poses import CALIBRATION_POSES, VERIFICATION_POSE, pose
from station.loop.fixture.screen import FixtureView, fixture_screen
from station.loop.screens import header, pad, serial_prompt, unit_screen, verdict_screen
from station.loop.slot import Slot, SlotState
from station.results.journal import JournalFile
from station.run.acquisition import StillnessThresholds
from station.run.capture import LiveView
from station.run.messages import Message
from station.run.operator_text import MAX_UNKNOWN, port_problem
from station.run.phases import Phase
from station.run.view import RunView
from tests.db.records import make_record

POSES = tuple(pose(n) for n in (*CALIBRATION_POSES, VERIFICATION_POSE))

#: Words each screen must show in the operator's language (and the English they replace).
UNIT_WORDS = {
    "ko": (
        "자세 3/7: 토우 위",
        "감지된 자세",
        "가속도",
        "키: r 마지막 자세 다시",
        "합격",
        "출하",
        "힐이 테이블에 닿음",
    ),
    "zh": (
        "姿态 3/7：趾部朝上",
        "工位检测到",
        "加速度",
        "按键：r 重做上一姿态",
        "合格",
        "出货",
        "跟部贴桌面",
    ),
}
FIXTURE_WORDS = {
    "ko": ("지그: 자세 3/7: 토우 위", "슬롯", "상태", "수리함", "다음 사이클", "측정 중"),
    "zh": ("治具：姿态 3/7：趾部朝上", "槽位", "状态", "返修箱", "下一轮", "采集中"),
}
ENGLISH = (
    "accel ▇",
    "gyro  ▇",
    "pose 3 of 7",
    "station sees",
    "keys:",
    "PASS",
    "FIXTURE: pose 3 of 7",
    "rework bin",
)


@pytest.fixture(autouse=True)
def english_after() -> Iterator[None]:
    yield
    set_language("en")


def _run_view(serial: str = "PT000001", *, said: tuple[Message, ...] = ()) -> RunView:
    sensed = Sensed(direction=np.array([0.0, 0.0, 1.0]), nearest=pose("toe_up"), nearest_deg=3.0)
    live = LiveView(
        sensed=sensed,
        matches=True,
        accel_std=np.array([1.5, 2.0, 1.0]),
        gyro_rate=np.array([0.2, 0.1, 0.3]),
        moving=False,
        progress=0.6,
    )
    return RunView(
        serial=serial,
        phase=Phase.POSE,
        poses=POSES,
        index=2,
        taken=frozenset({0, 1}),
        live=live,
        stillness=StillnessThresholds(),
        messages=said,
        wrong_unit=None,
    )


class _Running:
    """A slot's run as the fixture screen reads it: its phase, pose and view."""

    def __init__(self, serial: str) -> None:
        self._view = _run_view(serial)
        self.phase = Phase.POSE
        self.requested = POSES[2]
        self.verifying_gyros = False

    def view(self) -> RunView:
        return self._view


def _slots(tmp_path: Path) -> tuple[Slot, ...]:
    slots = tuple(
        Slot(n, f"/dev/ttyUSB{n}", JournalFile(tmp_path / f"slot{n}.json")) for n in (1, 2, 3, 4)
    )
    for slot, serial in zip(slots[:2], ("PT000011", "PT000012"), strict=True):
        slot.state = SlotState.RUNNING
        slot.serial = serial
        running: Any = _Running(serial)
        slot.run = running
    slots[2].state = SlotState.DONE
    slots[2].record = make_record(serial="PT000013", verdict="fail", disposition="rework")
    slots[3].state = SlotState.EMPTY
    return slots


def _fixture_view(tmp_path: Path) -> FixtureView:
    return FixtureView(
        stage="cycle",
        slots=_slots(tmp_path),
        scanning=None,
        typed="",
        offered=None,
        confirming=False,
        ahead=((1, "PT000021"),),
        ahead_typed="PT0000",
        poses=POSES,
        fixture_pose=2,
        resume=(),
        note=None,
        show_help=True,
    )


def _drawn(*screens: RenderableType) -> list[str]:
    console = Console(width=80, record=True, color_system=None)
    for screen in screens:
        console.print(screen)
    return console.export_text().splitlines()


def _station_screens() -> list[RenderableType]:
    record = make_record(serial="PT000001", verdict="pass", disposition="ship")
    return [
        Group(
            header("line1-st1", "op-7", "v0.1.0 · autocal-eq10 · limits kxm52", 3, (1, 2)),
            unit_screen(_run_view(said=(Message("warn", "capture refused: moved"),))),
        ),
        unit_screen(_run_view(), show_help=True),
        verdict_screen(record),
        serial_prompt("PT0000", "wrong pose: try again", queued="PT000002"),
    ]


@pytest.mark.parametrize("language", ["ko", "zh"])
def test_the_station_screen_fits_80_columns_in_the_operators_language(language: str) -> None:
    set_language(language)
    lines = _drawn(*_station_screens())
    assert max(map(cell_len, lines)) <= 80, [line for line in lines if cell_len(line) > 80]
    text = "\n".join(lines)
    for words in UNIT_WORDS[language]:
        assert words in text, words
    assert "station sees" not in text
    assert "keys:" not in text


@pytest.mark.parametrize("language", ["ko", "zh"])
def test_the_fixture_screen_fits_80_columns_in_the_operators_language(
    language: str, tmp_path: Path
) -> None:
    set_language(language)
    lines = _drawn(fixture_screen(_fixture_view(tmp_path)))
    assert max(map(cell_len, lines)) <= 80, [line for line in lines if cell_len(line) > 80]
    text = "\n".join(lines)
    for words in FIXTURE_WORDS[language]:
        assert words in text, words
    assert "FIXTURE" not in text
    assert "rework bin" not in text


def test_english_says_what_it_always_said(tmp_path: Path) -> None:
    text = "\n".join(_drawn(*_station_screens(), fixture_screen(_fixture_view(tmp_path))))
    for words in ENGLISH:
        assert words in text, words


def test_meter_labels_are_padded_by_cells_not_characters() -> None:
    assert pad("accel", 6) == "accel "
    assert cell_len(pad("가속도", 8)) == 8  # three double-width characters and two spaces
    assert pad("가속도", 6) == "가속도"


def test_an_unknown_error_is_cut_by_cells() -> None:
    said = port_problem(OSError("장치 오류 " * 20))
    assert cell_len(said) <= MAX_UNKNOWN
    assert said.endswith("…")
    assert said.startswith("장치 오류")
    assert port_problem(OSError("x" * 100)) == "x" * (MAX_UNKNOWN - 1) + "…"


#: A failed check's explanation on the verdict screen (code and serial as they are).
EXPLAINED = {
    "ko": "자세 잡음 x (자세 3) 8.59057 카운트: ≤ 8 벗어남",
    "zh": "姿态噪声 x （姿态 3） 8.59057 计数：超出 ≤ 8",
}


@pytest.mark.parametrize("language", ["ko", "zh"])
def test_the_failure_screen_explains_each_failure_in_the_operators_language(
    language: str,
) -> None:
    profile = load_profile().model_copy(update={"pose_noise_counts": Bounds(upper=8.0)})
    failure = check(profile, "pose_noise", 8.59057, axis="x", pose=2)
    assert failure is not None
    record = make_record(serial="PT000009", verdict="fail", failures=[failure.model_dump()])
    set_language(language)
    lines = _drawn(verdict_screen(record))
    assert max(map(cell_len, lines)) <= 80
    text = "\n".join(lines)
    assert f"✗ pose_noise: {EXPLAINED[language]}" in text
    assert "PT000009" in text
    assert failure.message not in text  # the record's English sentence, kept as said
    set_language("en")
    assert f"✗ pose_noise: {failure.message}" in "\n".join(_drawn(verdict_screen(record)))
