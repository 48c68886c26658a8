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

from station.domain import i18n
from station.domain.i18n import LANGUAGES, catalogue_text, set_language, tr

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
    for msgid, text in translated.items():
        # A line that names a count (ngettext): each of the language's forms has the
        # placeholders of the English plural.
        english = msgid[-1] if isinstance(msgid, tuple) else msgid
        for form in text if isinstance(text, tuple) else (text,):
            assert form, f"{language}: no translation of {msgid!r}"
            assert form not in (msgid if isinstance(msgid, tuple) else (msgid,)), (
                f"{language}: {msgid!r} left in English"
            )
            assert sorted(PLACEHOLDER.findall(form)) == sorted(PLACEHOLDER.findall(english)), msgid
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
