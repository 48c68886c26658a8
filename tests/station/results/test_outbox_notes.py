"""The outbox's notes to the operator in Korean and Chinese: the counts and the command
kept, the store's own words as it said them, no English word of the station's left."""

import re
from collections.abc import Iterator

import pytest

from station.domain.i18n import set_language
from station.results.outbox import SyncResult

#: Words that are no language: the command the operator types, the store's own error.
KEPT = {"calstation", "outbox", "list", "HTTP"}
#: Each note in the operator's language: (the sync, the words it must show).
NOTES = {
    "ko": (
        "실행 3건이 전송 대기 중: HTTP 503",
        "저장소가 실행 1건에서 계속 실패합니다 (HTTP 503)",
        "2건 거부됨, 1건 읽을 수 없음 따로 보관됨: calstation outbox list 참조",
    ),
    "zh": (
        "3 次运行在发件箱中等待: HTTP 503",
        "存储在 1 次运行 上持续失败（HTTP 503）",
        "2 条被拒和1 条无法读取已搁置：见 calstation outbox list",
    ),
}


@pytest.fixture(autouse=True)
def english_after() -> Iterator[None]:
    yield
    set_language("en")


def _sync() -> SyncResult:
    return SyncResult(
        stored=0,
        refused=2,
        pending=3,
        error="HTTP 503",
        unreadable=1,
        failing=1,
        failure="HTTP 503",
    )


@pytest.mark.parametrize("language", ["ko", "zh"])
def test_the_outbox_note_reads_in_the_operators_language(language: str) -> None:
    set_language(language)
    note = _sync().note()
    assert note is not None
    for words in NOTES[language]:
        assert words in note, (words, note)
    assert set(re.findall(r"[A-Za-z]{2,}", note)) <= KEPT, note
    assert "{" not in note


def test_english_notes_say_what_they_always_said() -> None:
    assert _sync().note() == (
        "3 runs wait in the outbox: HTTP 503 · the store keeps failing on 1 run (HTTP 503): "
        "retried with backoff, the others are sent · 2 refused and 1 unreadable set aside: "
        "see calstation outbox list"
    )
