"""The screens in Korean and Chinese keep their layout in 80 columns: every line fits in
80 terminal cells (a Hangul or Han character takes two), and the operator reads their
own language."""

import io
import re
from collections.abc import Iterator
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from babel.messages.pofile import read_po
from rich.cells import cell_len
from rich.console import Console, Group, RenderableType
from rich.live_render import LiveRender
from rich.text import Text

from station.cli.output import screen_console
from station.device import SerialNumberMismatchError
from station.domain.i18n import LANGUAGES, catalogue_text, set_language, tr, trn
from station.domain.product.limits import Bounds, check, load_profile
from station.domain.signals.orientation import Sensed
from station.domain.signals.poses import CALIBRATION_POSES, VERIFICATION_POSE, pose
from station.domain.signals.poses import POSES as NAMED_POSES
from station.loop.fixture.screen import FixtureView, fixture_screen, scan_keys_help
from station.loop.fixture.screen import keys_help as fixture_keys_help
from station.loop.screens import (
    KeysLine,
    header,
    keys_help,
    pad,
    serial_prompt,
    unit_screen,
    verdict_screen,
)
from station.loop.slot import Slot, SlotState
from station.loop.unit_history import UnitHistory
from station.results.journal import JournalFile
from station.run.acquisition import StillnessThresholds
from station.run.capture import LiveView
from station.run.messages import Message
from station.run.operator_text import (
    MAX_UNKNOWN,
    port_problem,
    pose_words,
    said_of,
    serial_mismatch,
)
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
    assert "✗ " + said_of("pose_noise", EXPLAINED[language]) in text
    assert "PT000009" in text
    assert failure.message not in text  # the record's English sentence, kept as said
    set_language("en")
    assert f"✗ pose_noise: {failure.message}" in "\n".join(_drawn(verdict_screen(record)))


# -- every line fits, at any width, in every language -------------------------------------

#: The whole-unit plan's poses: the six, the six corners, the verification pose.
CORNERS = tuple(n for n in NAMED_POSES if n not in (*CALIBRATION_POSES, VERIFICATION_POSE))
WHOLE_UNIT = tuple(pose(n) for n in (*CALIBRATION_POSES, *CORNERS, VERIFICATION_POSE))
#: A value for every ``{placeholder}`` of a message drawn on its own.
FILLER = "PT002007"
PLACEHOLDER = re.compile(r"\{(\w+)\}")


def _on_live(width: int, *screens: RenderableType) -> list[str]:
    """``screens`` drawn as the station draws them: each as rich's ``Live`` display draws
    it (its ``LiveRender``), on the console the station uses (:func:`screen_console`), in
    a terminal ``width`` columns wide (and tall enough for the tallest screen)."""
    console = screen_console(
        width=width, height=500, record=True, color_system=None, file=io.StringIO()
    )
    for screen in screens:
        console.print(LiveRender(screen))
        console.line()
    return console.export_text().splitlines()


def _catalogue_lines() -> list[str]:
    """Every line the catalogues hold, in the operator's language, its values filled."""
    lines = []
    for message in read_po(io.StringIO(catalogue_text("ko"))):  # the ids; tr translates them
        if isinstance(message.id, str) and message.id:
            lines.append(tr(message.id, **dict.fromkeys(PLACEHOLDER.findall(message.id), FILLER)))
        elif message.id:  # words after a count: both forms
            singular, plural = message.id
            values = dict.fromkeys(PLACEHOLDER.findall(plural), FILLER)
            values.pop("count", None)
            lines += [trn(singular, plural, n, **values) for n in (1, 12)]
    return lines


def _every_screen(tmp_path: Path) -> tuple[list[RenderableType], list[str]]:
    """Every screen the station draws, and the sentences they hold (whose words must stay
    whole): the header, the unit at a pose (seven poses, and the whole unit's thirteen),
    its help, the verdict, the serial prompt under each refusal, the fixture."""
    mismatch = SerialNumberMismatchError("PT002007", "PT002006")
    record = make_record(serial="PT000001", verdict="pass", disposition="ship")
    failed = make_record(serial="PT002007", verdict="fail", disposition="rework")
    sentences = [
        serial_mismatch(mismatch.expected, mismatch.reported),
        UnitHistory("PT002007", runs=(failed,)).at_scan(3, failed.part_number).text or "",
        keys_help(),
        *_catalogue_lines(),
    ]
    whole = replace(_run_view(), poses=WHOLE_UNIT, index=9, taken=frozenset(range(9)))
    screens: list[RenderableType] = [
        Group(
            header("line1-st1", "op-7", "v0.1.0 · autocal-ls9 · limits whole-unit", 3, (1, 2)),
            unit_screen(_run_view(said=(Message("warn", sentences[0]),))),
        ),
        unit_screen(whole),
        unit_screen(_run_view(), show_help=True),
        verdict_screen(record),
        *(serial_prompt("PT0000", sentence, queued="PT000002") for sentence in sentences),
        fixture_screen(_fixture_view(tmp_path)),
    ]
    return screens, sentences


def _cut_words(lines: list[str], sentences: list[str], width: int) -> list[str]:
    """The words of ``sentences`` that no line shows whole (a word wider than the screen
    is folded, as it must be)."""
    return sorted(
        {
            word
            for sentence in sentences
            for word in sentence.split()
            if cell_len(word) < width - 8 and not any(word in line for line in lines)
        }
    )


@pytest.mark.parametrize("width", [80, 120])
@pytest.mark.parametrize("language", LANGUAGES)
def test_every_line_fits_the_terminal_and_no_word_is_cut(
    language: str, width: int, tmp_path: Path
) -> None:
    set_language(language)
    screens, sentences = _every_screen(tmp_path)
    lines = _on_live(width, *screens)
    assert [line for line in lines if cell_len(line) > width] == []
    assert _cut_words(lines, sentences, width) == []
    strip = [f"{i + 1} {pose_words(p.name)}" for i, p in enumerate(WHOLE_UNIT)]
    assert [item for item in strip if not any(item in line for line in lines)] == []


@pytest.mark.parametrize("width", [80, 120])
@pytest.mark.parametrize("language", LANGUAGES)
def test_the_keys_lines_wrap_between_keys_never_inside_one(
    language: str, width: int, tmp_path: Path
) -> None:
    """Each key and what it does ("r redo last pose") stays on one line of the unit's and
    the fixture's screens; each language's keys line lists as many keys as English's."""
    said = (keys_help, fixture_keys_help, scan_keys_help)
    english = [len(KeysLine(line()).keys) for line in said]
    set_language(language)
    cycle = replace(_fixture_view(tmp_path), show_help=False)
    scan = replace(cycle, stage="scan", scanning=cycle.slots[3])
    lines = _on_live(width, unit_screen(_run_view()), fixture_screen(cycle), fixture_screen(scan))
    for line, count in zip((line() for line in said), english, strict=True):
        keys = KeysLine(line).keys
        assert len(keys) == count, keys
        assert [key for key in keys if not any(key in drawn for drawn in lines)] == [], lines


def test_a_screen_on_a_soft_wrapping_console_would_lose_the_ends_of_its_lines() -> None:
    """The check above can fail: rich's ``Live`` on a soft-wrapping console crops."""
    sentence = keys_help()
    console = Console(
        width=80, height=500, record=True, color_system=None, file=io.StringIO(), soft_wrap=True
    )
    console.print(LiveRender(Text(sentence)))
    assert _cut_words(console.export_text().splitlines(), [sentence], 80) != []


@pytest.mark.parametrize(
    ("language", "said"),
    [
        ("ko", "시리얼 번호 불일치: 라벨은 'PT002007', 유닛은 'PT002006'을 보고합니다"),
        ("zh", "序列号不符：标签为 'PT002007'，产品报告 'PT002006'"),
    ],
)
def test_the_serial_number_mismatch_is_said_whole_in_the_operators_language(
    language: str, said: str
) -> None:
    set_language(language)
    sentence = serial_mismatch("PT002007", "PT002006")
    assert sentence.startswith(said)
    assert re.findall(r"[A-Za-z]{2,}", re.sub(r"'PT\d+'", "", sentence)) == []
