"""The reader's language of a page: ``?lang=`` or else the ``Accept-Language`` header.

``?lang=`` names one of the shipped languages (:data:`station.domain.i18n.LANGUAGES`;
another is refused, 422); without it the header's preferences are taken in the order of
their weights (RFC 9110 §12.5.4: ``ko-KR,ko;q=0.9,en;q=0.8``), each by its primary
subtag, and the first shipped one wins; a header that names none, or cannot be read, is
no error: English.
"""

from typing import Annotated, cast

from fastapi import Depends, Header, Query, Request

from station.domain.i18n import LANGUAGES, Language


def preferred(header: str | None) -> Language:
    """The first shipped language of an ``Accept-Language`` header; English if none."""
    ranked: list[tuple[float, int, str]] = []
    for position, item in enumerate((header or "").split(",")):
        tag, _, parameters = item.strip().partition(";")
        weight = 1.0
        name, _, value = parameters.strip().partition("=")
        if name.strip().lower() == "q":
            try:
                weight = float(value)
            except ValueError:
                continue
        ranked.append((-weight, position, tag.strip().split("-")[0].lower()))
    for weight, _, primary in sorted(ranked):
        if weight < 0 and primary in LANGUAGES:
            return cast(Language, primary)
    return "en"


def page_language(
    lang: Annotated[
        Language | None,
        Query(description="the page's language (default: the Accept-Language header's, else en)"),
    ] = None,
    accept_language: Annotated[str | None, Header(include_in_schema=False)] = None,
) -> Language:
    """The language a page is written in: ``?lang=``, else ``Accept-Language``, else en."""
    return lang if lang is not None else preferred(accept_language)


LanguageDep = Annotated[Language, Depends(page_language)]


def request_language(request: Request) -> Language:
    """The language of a page answering ``request`` outside a route (a refusal's page):
    its ``?lang=`` when shipped, else its ``Accept-Language``, else en."""
    lang = request.query_params.get("lang")
    if lang in LANGUAGES:
        return cast(Language, lang)
    return preferred(request.headers.get("accept-language"))
