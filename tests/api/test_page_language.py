"""Every page in the reader's language: ``?lang=`` or else ``Accept-Language``
(:mod:`api.language`), one answer (422 naming ``lang``) to a language not shipped, and no
English words left on a page in Korean or Chinese but names, units and values."""

import re
from html.parser import HTMLParser

import httpx
import pytest

from db import Database
from station.domain.i18n import LANGUAGES
from tests.api.every_page import PAGES, store_plant

#: Words a page in any language shows as they are: units, statistics' and standards'
#: names, file formats, the time zone.
KEPT = {
    "counts", "deg", "Cp", "Cpk", "LSL", "USL", "UCL", "LCL", "ppm", "sd", "IQR", "MR",
    "Tukey", "Western", "Electric", "JSON", "CSV", "HTML", "TOML", "SHA", "UTC", "calstation",
}  # fmt: skip
#: A word of English: letters only (a serial, code or identifier has a digit, "_" or "-").
WORD = re.compile(r"[A-Za-z]{2,}")
#: Elements whose text is a name or a value as stored, never a word of the page.
NAMES = {"script", "style", "code"}
#: Elements whose every word is the page's: a heading, a column's name, a field's label.
LABELS = {"title", "h1", "h2", "h3", "th", "label", "button"}


class _Text(HTMLParser):
    """The text a reader sees on a page (and its title), without names and values kept
    as stored: serials (``a.serial``), code, scripts."""

    def __init__(self) -> None:
        super().__init__()
        self.parts: list[str] = []
        self.labels: list[str] = []
        self._skipping: list[str] = []
        self._open: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        classes = (dict(attrs).get("class") or "").split()
        if self._skipping or tag in NAMES or "serial" in classes:
            if tag not in {"br", "input", "img", "meta", "link"}:
                self._skipping.append(tag)
        else:
            self._open.append(tag)
            self.parts.append("\n")

    def handle_endtag(self, tag: str) -> None:
        if self._skipping and self._skipping[-1] == tag:
            self._skipping.pop()
        elif tag in self._open:
            del self._open[len(self._open) - 1 - self._open[::-1].index(tag) :]
        self.parts.append("\n")

    def handle_data(self, data: str) -> None:
        if not self._skipping:
            self.parts.append(data)
            if LABELS & set(self._open):
                self.labels.append(data)


def _words(text: str) -> list[str | None]:
    """The text's tokens: an English word (not :data:`KEPT`), else None."""
    tokens = [token.strip(",;:.()[]…·–—→←|\"'“”") for token in text.split()]
    return [t if WORD.fullmatch(t) and t not in KEPT else None for t in tokens]


def english_phrases(page: str) -> list[str]:
    """English left on a page: runs of two or more English words in its visible text,
    and any English word of a heading, column name or label (not :data:`KEPT`)."""
    reader = _Text()
    reader.feed(page)
    found = [word for label in reader.labels for word in _words(label) if word]
    for line in "".join(reader.parts).splitlines():
        run: list[str] = []
        for word in [*_words(line), None]:
            if word:
                run.append(word)
                continue
            if len(run) >= 2:
                found.append(" ".join(run))
            run = []
    return found


@pytest.fixture
def plant(client: httpx.Client, database: Database) -> httpx.Client:
    store_plant(database)
    return client


def test_english_phrases_are_found_and_names_are_not() -> None:
    page = (
        '<p>자세 잡음 x 8.59 counts: 오프셋 (Cpk 1.2) <a class="serial">PT A B</a>'
        "<code>calstation keys create</code> line1-st1 operator-with-a-long-name</p>"
        "<td>moving range</td><th>Runs</th><td>runs</td><svg><text>latest 3 of 9 runs in range"
        "</text></svg>"
    )
    assert english_phrases(page) == ["Runs", "moving range", "runs in range"]


def test_every_page_takes_lang_and_accept_language_and_is_written_in_it(
    plant: httpx.Client,
) -> None:
    for name, path in PAGES.items():
        joiner = "&" if "?" in path else "?"
        for language in LANGUAGES:
            page = plant.get(f"{path}{joiner}lang={language}")
            assert page.status_code == 200, (name, language, page.text[:300])
            assert f'<html lang="{language}">' in page.text, (name, language)
            heard = plant.get(path, headers={"Accept-Language": f"{language};q=0.9, fr"})
            assert f'<html lang="{language}">' in heard.text, (name, language)
            if language != "en":
                left = sorted(set(english_phrases(page.text)))
                assert left == [], (name, language, left)
        english = plant.get(path, headers={"Accept-Language": "fr-FR, de;q=0.5"})
        assert '<html lang="en">' in english.text, name
        assert english_phrases(english.text), name  # the check reads the English page


@pytest.mark.parametrize("value", ["fr", "KO", "", "ko-KR"])
def test_every_page_refuses_a_language_it_does_not_ship_in_one_way(
    plant: httpx.Client, value: str
) -> None:
    for name, path in PAGES.items():
        joiner = "&" if "?" in path else "?"
        refused = plant.get(f"{path}{joiner}lang={value}")
        assert refused.status_code == 422, (name, value)
        assert "lang" in refused.text, name


@pytest.mark.parametrize(
    ("language", "title"), [("en", "End-of-line report"), ("ko", "라인 최종 검사 보고서")]
)
def test_a_refused_page_is_in_the_readers_language_too(
    plant: httpx.Client, language: str, title: str
) -> None:
    refused = plant.get(
        "/api/v1/reports/eol",
        params={"format": "html", "from": "14.13.2026"},
        headers={"Accept-Language": language},
    )
    assert refused.status_code == 422
    assert f'<html lang="{language}">' in refused.text
    assert f"<h1>{title}</h1>" in refused.text
    assert 'id="problem"' in refused.text
