"""The operator's language: gettext catalogues of the lines the station says (en, ko, zh).

The catalogues are ``station/domain/locale/LANG/LC_MESSAGES/calstation.po`` (Babel's
gettext format, extracted from the sources with ``pybabel extract``, see
``docs/station.md``); English is the sources' own text. :func:`set_language` chooses the
process's language once, at start (``language`` in the station's configuration,
``CALSTATION_LANGUAGE``, ``--language``); :func:`tr` translates a message and fills its
``{placeholders}`` afterwards, so a translation may put them in its own order; :func:`trn`
translates one whose words follow a count ("1 run", "3 runs"). A server
that answers each request in its reader's language (``?lang=``, ``Accept-Language``)
takes :func:`speaker` of that language instead, and :func:`counter` for a line that
names a count (gettext's plural forms: one form in Korean and Chinese, two in English).
Babel is imported only when a language
other than English is chosen.

Korean particles depend on the sound the word before them ends in, which a placeholder
leaves open until it is filled: a Korean translation writes both (``{serial}은(는)``,
``이(가)``, ``을(를)``, ``과(와)``, ``(으)로``) and :func:`korean_particles` keeps the one
the filled line needs (the first after a final consonant, *batchim*; ``로`` after a vowel
or ㄹ), reading digits and Latin letters as Korean reads them aloud.
"""

import functools
import gettext
import io
import re
from collections.abc import Callable
from importlib import resources
from typing import Final, Literal, cast, get_args

Language = Literal["en", "ko", "zh"]
#: The shipped languages: English (the sources), Korean, Simplified Chinese.
LANGUAGES: Final[tuple[str, ...]] = get_args(Language)
#: The catalogues' gettext domain.
DOMAIN: Final = "calstation"

#: A translation function: a message in one language, its ``{placeholders}`` filled.
Say = Callable[..., str]
#: A translation function of a line that names a count: ``(singular, plural, count,
#: **values)``, the form of ``count`` in one language, ``{count}`` and the values filled.
Count = Callable[..., str]

_language: Language = "en"


def catalogue_text(language: str) -> str:
    """The ``.po`` catalogue of ``language`` as shipped."""
    path = resources.files("station.domain").joinpath(
        "locale", language, "LC_MESSAGES", f"{DOMAIN}.po"
    )
    return path.read_text(encoding="utf-8")


@functools.cache
def _compiled(language: str) -> gettext.GNUTranslations:
    """``language``'s catalogue compiled in memory (Babel's reader and writer), once."""
    from babel.messages.mofile import write_mo
    from babel.messages.pofile import read_po

    catalog = read_po(io.StringIO(catalogue_text(language)), locale=language, domain=DOMAIN)
    compiled = io.BytesIO()
    write_mo(compiled, catalog)
    compiled.seek(0)
    return gettext.GNUTranslations(compiled)


def _translations_of(language: str) -> gettext.NullTranslations:
    if language not in LANGUAGES:
        raise ValueError(f"unknown language {language!r}; shipped: {', '.join(LANGUAGES)}")
    return gettext.NullTranslations() if language == "en" else _compiled(language)


def set_language(language: str) -> None:
    """Say the operator's lines in ``language`` from now on (one of :data:`LANGUAGES`)."""
    global _language
    _translations_of(language)  # refuses a language not shipped; compiles its catalogue once
    _language = cast(Language, language)  # one of LANGUAGES: _translations_of checked it


def language() -> Language:
    """The operator's language, as :func:`set_language` chose it (English by default)."""
    return _language


def tr(message: str, **values: object) -> str:
    """``message`` in the operator's language, its ``{placeholders}`` filled."""
    return speaker(_language)(message, **values)


def trn(singular: str, plural: str, count: int, **values: object) -> str:
    """``singular`` or ``plural`` as ``count`` and the operator's language want it (gettext's
    plural forms: Korean and Chinese have one), its ``{placeholders}`` and ``{count}``
    filled."""
    return counter(_language)(singular, plural, count, **values)


def speaker(language: str) -> Say:
    """:func:`tr` in ``language`` (one of :data:`LANGUAGES`), whatever the process's."""
    translations = _translations_of(language)

    def say(message: str, **values: object) -> str:
        return _filled(language, translations.gettext(message), values)

    return say


def _filled(language: str, text: str, values: dict[str, object]) -> str:
    said = text.format(**values)
    return korean_particles(said) if language == "ko" else said


#: A particle written for both endings: after a final consonant, then after a vowel.
_PARTICLE = re.compile(r"(은|이|을|과)\((는|가|를|와)\)|\(으\)로")
#: How each digit is read: its final sound (``c`` consonant, ``l`` ㄹ, ``v`` vowel):
#: 영 일 이 삼 사 오 육 칠 팔 구 (a number ending in 0 is read 십, 백, 천, 만: consonants).
_DIGIT_ENDS = dict(zip("0123456789", "clvcvvcllv", strict=True))
#: Latin letters read aloud whose names end in a consonant: 엘, 알 (ㄹ); 엠, 엔.
_LETTER_ENDS = {"l": "l", "r": "l", "m": "c", "n": "c"}
_CLOSING = {")": "(", "）": "（", "]": "["}


def _final_sound(before: str) -> str:
    """The sound ``before`` ends in when read aloud: ``c`` a consonant, ``l`` ㄹ, ``v`` a
    vowel. Quotes are passed over; a word in brackets is, too (the particle goes with the
    word before them)."""
    i = len(before) - 1
    while i >= 0:
        char = before[i]
        if char in "'\"’”":
            i -= 1
        elif char in _CLOSING:
            i = before.rfind(_CLOSING[char], 0, i) - 1
            if i < -1:
                return "v"
        else:
            break
    if i < 0:
        return "v"
    char = before[i]
    if "가" <= char <= "힣":
        final = (ord(char) - ord("가")) % 28
        return "v" if final == 0 else "l" if final == 8 else "c"
    if char in _DIGIT_ENDS:
        return _DIGIT_ENDS[char]
    return _LETTER_ENDS.get(char.lower(), "v")


def korean_particles(text: str) -> str:
    """``text`` with each particle written for both endings (``은(는)``) reduced to the
    one the word before it takes."""

    def chosen(match: re.Match[str]) -> str:
        sound = _final_sound(text[: match.start()])
        if match.group(0) == "(으)로":
            return "으로" if sound == "c" else "로"
        return match.group(1) if sound != "v" else match.group(2)

    return _PARTICLE.sub(chosen, text)


#: :func:`speaker` of English: the sources' own text.
ENGLISH: Final[Say] = speaker("en")


def counter(language: str) -> Count:
    """The lines of ``language`` (one of :data:`LANGUAGES`) that name a count, each in
    the plural form the language gives that count (gettext ``ngettext``)."""
    translations = _translations_of(language)

    def count(singular: str, plural: str, number: int, **values: object) -> str:
        chosen = translations.ngettext(singular, plural, number)
        return _filled(language, chosen, {"count": number, **values})

    return count
