"""The outbox's notes to the operator in Korean and Chinese: the counts and the command
kept, the store's own words as it said them, no English word of the station's left."""

import re
from collections.abc import Iterator
from pathlib import Path
from uuid import uuid4

import pytest

from db import Database
from station.domain.i18n import set_language
from station.results.outbox import Outbox, SyncResult
from station.results.storage import DatabaseStore

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


@pytest.mark.parametrize(
    ("language", "said"),
    [("ko", "읽을 수 없고 따로 옮길 수도 없음: "), ("zh", "无法读取，也无法移到一旁：")],
)
def test_an_unreadable_file_that_cannot_be_set_aside_is_said_in_the_operators_language(
    tmp_path: Path, database: Database, language: str, said: str
) -> None:
    outbox = Outbox(tmp_path / "outbox")
    bad = outbox.directory / f"{uuid4()}.json"
    bad.write_bytes(b"{")
    outbox.unreadable_dir.write_text("a file where the folder would go\n")  # mkdir fails
    set_language(language)
    result = outbox.sync(DatabaseStore(database=database))
    assert result.failing == 1
    assert result.failure is not None
    assert result.failure.startswith(said), result.failure
    assert bad.read_bytes() == b"{"  # nothing lost: it stays in the queue
