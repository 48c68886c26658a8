"""The operator's language: gettext catalogues of the lines the station says (en, ko, zh).

The catalogues are ``station/domain/locale/LANG/LC_MESSAGES/calstation.po`` (Babel's
gettext format, extracted from the sources with ``pybabel extract``, see
``docs/station.md``); English is the sources' own text. :func:`set_language` chooses the
process's language once, at start (``language`` in the station's configuration,
``CALSTATION_LANGUAGE``, ``--language``); :func:`tr` translates a message and fills its
``{placeholders}`` afterwards, so a translation may put them in its own order. A server
that answers each request in its reader's language (``?lang=``, ``Accept-Language``)
takes :func:`speaker` of that language instead, and :func:`counter` for a line that
names a count (gettext's plural forms: one form in Korean and Chinese, two in English).
Babel is imported only when a language
other than English is chosen.
"""

import functools
import gettext
import io
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

_translations: gettext.NullTranslations = gettext.NullTranslations()
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
    global _translations, _language
    _translations = _translations_of(language)
    _language = cast(Language, language)  # one of LANGUAGES: _translations_of checked it


def language() -> Language:
    """The operator's language, as :func:`set_language` chose it (English by default)."""
    return _language


def tr(message: str, **values: object) -> str:
    """``message`` in the operator's language, its ``{placeholders}`` filled."""
    return _translations.gettext(message).format(**values)


def speaker(language: str) -> Say:
    """:func:`tr` in ``language`` (one of :data:`LANGUAGES`), whatever the process's."""
    translations = _translations_of(language)

    def say(message: str, **values: object) -> str:
        return translations.gettext(message).format(**values)

    return say


#: :func:`speaker` of English: the sources' own text.
ENGLISH: Final[Say] = speaker("en")


def counter(language: str) -> Count:
    """The lines of ``language`` (one of :data:`LANGUAGES`) that name a count, each in
    the plural form the language gives that count (gettext ``ngettext``)."""
    translations = _translations_of(language)

    def count(singular: str, plural: str, number: int, **values: object) -> str:
        return translations.ngettext(singular, plural, number).format(count=number, **values)

    return count
