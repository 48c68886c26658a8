"""The operator's language: every line the station says through the catalogues has a
translation in each shipped language, with the same placeholders, and the template is
what the sources say."""

import io
import re
from collections.abc import Iterator
from pathlib import Path

import pytest
from babel.messages.extract import extract_from_dir
from babel.messages.frontend import parse_mapping_cfg
from babel.messages.pofile import read_po
from hypothesis import given
from hypothesis import strategies as st

from station.domain import i18n
from station.domain.i18n import LANGUAGES, catalogue_text, set_language, tr, trn
from station.run.operator_text import said_of

ROOT = Path(__file__).resolve().parents[3]
TEMPLATE = ROOT / "station" / "domain" / "locale" / "calstation.pot"
#: How ``pybabel extract -F babel.cfg`` reads each file: the sources and the page templates.
METHODS, OPTIONS = parse_mapping_cfg(io.StringIO((ROOT / "babel.cfg").read_text(encoding="utf-8")))
#: The folders ``pybabel extract`` reads (docs/station.md).
EXTRACTED = ("station/run", "station/loop", "station/cli", "station/report", "station/results")
PLACEHOLDER = re.compile(r"\{(\w+)\}")


@pytest.fixture(autouse=True)
def english_after() -> Iterator[None]:
    yield
    set_language("en")


def _template_ids() -> set[str]:
    return {m.id for m in read_po(io.StringIO(TEMPLATE.read_text(encoding="utf-8"))) if m.id}


def test_the_template_holds_every_line_the_sources_translate() -> None:
    said = {
        message
        for folder in EXTRACTED
        for _, _, message, _, _ in extract_from_dir(
            ROOT / folder,
            method_map=METHODS,
            options_map=OPTIONS,
            keywords={"tr": None, "trn": (1, 2)},
            comment_tags=(),
        )
    }
    assert said == _template_ids()
    assert len(said) >= 12


@pytest.mark.parametrize("language", [lang for lang in LANGUAGES if lang != "en"])
def test_every_message_has_a_translation_with_the_same_placeholders(language: str) -> None:
    catalogue = read_po(io.StringIO(catalogue_text(language)), locale=language)
    translated = {m.id: m.string for m in catalogue if m.id}
    assert set(translated) == _template_ids()
    for msgid, string in translated.items():
        # A message whose words follow a count has its forms (one in Korean and Chinese).
        ids = (msgid,) if isinstance(msgid, str) else msgid
        for text in (string,) if isinstance(string, str) else string:
            assert text, f"{language}: no translation of {msgid!r}"
            words = re.search(r"[A-Za-z]", PLACEHOLDER.sub("", ids[0]))  # not punctuation only
            assert text not in ids or not words, f"{language}: {msgid!r} left in English"
            for said in ids:
                assert sorted(set(PLACEHOLDER.findall(text))) == sorted(
                    set(PLACEHOLDER.findall(said))
                ), msgid
    assert not any(m.fuzzy for m in catalogue if m.id)


def test_a_line_in_korean_and_chinese_keeps_its_values() -> None:
    line = "pose {number} ({pose}) captured"
    assert tr(line, number=3, pose="toe up") == "pose 3 (toe up) captured"
    set_language("ko")
    assert tr(line, number=3, pose="toe up") == "자세 3(toe up) 측정 완료"
    set_language("zh")
    assert tr(line, number=3, pose="toe up") == "姿态 3（toe up）已采集"
    set_language("en")
    assert tr(line, number=3, pose="toe up") == "pose 3 (toe up) captured"


@pytest.mark.parametrize(
    ("language", "one", "two"),
    [
        ("en", "1 file set aside", "2 files set aside"),
        ("ko", "파일 1개 보류됨", "파일 2개 보류됨"),
        ("zh", "1 个文件已搁置", "2 个文件已搁置"),
    ],
)
def test_a_line_that_names_a_count_takes_the_form_of_its_count(
    language: str, one: str, two: str
) -> None:
    count = i18n.counter(language)
    line = ("{count} file set aside", "{count} files set aside")
    assert count(*line, 1) == one
    assert count(*line, 2) == two


def test_an_unknown_language_is_refused() -> None:
    with pytest.raises(ValueError, match="unknown language 'fr'; shipped: en, ko, zh"):
        set_language("fr")
    assert isinstance(i18n.LANGUAGES, tuple)


# -- Korean particles: chosen by the sound the word before them ends in --------------------

#: The particles written for both endings, and which one follows a final consonant
#: (batchim) and which a vowel.
PAIRS = {
    "은(는)": ("은", "는"),
    "이(가)": ("이", "가"),
    "을(를)": ("을", "를"),
    "과(와)": ("과", "와"),
}
HANGUL = st.integers(0xAC00, 0xD7A3).map(chr)


@given(word=st.text(HANGUL, min_size=1, max_size=4), pair=st.sampled_from(sorted(PAIRS)))
def test_a_korean_particle_follows_the_last_syllable(word: str, pair: str) -> None:
    set_language("ko")
    batchim = (ord(word[-1]) - 0xAC00) % 28 != 0
    after_consonant, after_vowel = PAIRS[pair]
    said = tr("{word}" + pair + " 있습니다", word=word)
    assert said == word + (after_consonant if batchim else after_vowel) + " 있습니다"


@given(word=st.text(HANGUL, min_size=1, max_size=4))
def test_ro_takes_eu_after_a_consonant_other_than_rieul(word: str) -> None:
    set_language("ko")
    final = (ord(word[-1]) - 0xAC00) % 28
    said = tr("{word}(으)로", word=word)
    assert said == word + ("으로" if final not in (0, 8) else "로")


@pytest.mark.parametrize(
    ("value", "said"),
    [
        ("PT002007", "PT002007은"),  # 칠
        ("3", "3은"),  # 삼
        ("2", "2는"),  # 이
        ("'PT002004'", "'PT002004'는"),  # 사, inside quotes
        ("3(토우 위)", "3(토우 위)은"),  # the word before the brackets
        ("10", "10은"),  # 십
    ],
)
def test_a_particle_after_a_number_follows_how_it_is_read(value: str, said: str) -> None:
    set_language("ko")
    assert tr("{value}은(는)", value=value) == said


@given(count=st.integers(0, 10_000))
def test_words_that_follow_a_count_take_its_form(count: int) -> None:
    set_language("en")
    runs = trn("{count} run waits in the outbox", "{count} runs wait in the outbox", count)
    assert runs == (
        f"{count} run waits in the outbox" if count == 1 else f"{count} runs wait in the outbox"
    )
    set_language("ko")
    runs = trn("{count} run waits in the outbox", "{count} runs wait in the outbox", count)
    assert runs == f"실행 {count}건이 전송 대기 중"


def test_a_value_and_what_is_said_of_it_take_the_languages_colon() -> None:
    assert said_of("PT000001", "PASS") == "PT000001: PASS"
    set_language("zh")
    assert said_of("PT000001", "合格") == "PT000001：合格"
    set_language("ko")
    assert said_of("PT000001", "합격") == "PT000001: 합격"


def test_no_korean_line_keeps_both_particles() -> None:
    set_language("ko")
    catalogue = read_po(io.StringIO(catalogue_text("ko")), locale="ko")
    for message in catalogue:
        if not message.id or not isinstance(message.id, str):
            continue
        values = {name: "PT002007" for name in PLACEHOLDER.findall(message.id)}
        said = tr(message.id, **values)
        assert not re.search(r"\((는|가|를|와|으)\)", said), said
