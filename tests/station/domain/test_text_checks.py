"""Every checked text field refuses a control character anywhere in it, a trailing newline
included (``^…$`` matched with ``re.match`` let one through), and keeps the texts it is
meant to hold: free text (failure messages, capture reasons, gyro sources and moves,
review reasons, a limits profile's description, the gyro documents' strings) and the
names pydantic matches against a pattern (station, operator, lot, serial, profile)."""

from collections.abc import Callable

import pytest
from hypothesis import given
from hypothesis import strategies as st
from pydantic import BaseModel, TypeAdapter

from station.domain.constants import IDENTIFIER_PATTERN, Identifier
from station.domain.product.limits import LimitsProfile, load_profile
from station.domain.record.records import (
    SERIAL_PATTERN,
    FailureReason,
    GyroMove,
    LogSource,
    Reason,
    ReplacedCapture,
    Serial,
)
from station.domain.sensors.record_bounds import plain_document


class _Document(BaseModel):
    """A document stored whole as JSON, as a gyro fit's report is."""

    note: str


_CAPTURE = {
    "captured_at": "2026-11-02T08:00:05Z",
    "mean": {"x": 2048, "y": 2050, "z": 2900},
    "std": {"x": 40, "y": 35, "z": 50},
    "sample_count": 1024,
}
_PROFILE = load_profile().document

#: Texts without a control character (Unicode category Cc) and without surrogates.
FREE = st.text(st.characters(exclude_categories=["Cc", "Cs"]), max_size=40)

#: Each checked field: a function validating a text in it, and the texts it holds.
CHECKS: dict[str, tuple[Callable[[str], object], st.SearchStrategy[str]]] = {
    "failure message": (lambda t: FailureReason(code="offset", message=t), FREE),
    "capture reason": (lambda t: ReplacedCapture.model_validate({**_CAPTURE, "reason": t}), FREE),
    "gyro move unusable": (lambda t: GyroMove(before=0, after=1, unusable=t), FREE),
    "gyro source": (TypeAdapter(LogSource).validate_python, FREE.filter(bool)),
    "review reason": (TypeAdapter(Reason).validate_python, FREE.filter(str.strip)),
    "profile description": (
        lambda t: LimitsProfile.model_validate({**_PROFILE, "description": t}),
        FREE,
    ),
    "gyro document text": (lambda t: plain_document(_Document(note=t)), FREE),
    "identifier": (
        TypeAdapter(Identifier).validate_python,
        st.from_regex(IDENTIFIER_PATTERN, fullmatch=True),
    ),
    "serial": (TypeAdapter(Serial).validate_python, st.from_regex(SERIAL_PATTERN, fullmatch=True)),
    "profile name": (
        lambda t: LimitsProfile.model_validate({**_PROFILE, "name": t}),
        st.from_regex(IDENTIFIER_PATTERN, fullmatch=True),
    ),
}


def _refused(check: Callable[[str], object], text: str) -> bool:
    """Whether ``check`` refuses ``text`` (pydantic's ValidationError is a ValueError)."""
    try:
        check(text)
    except ValueError:
        return True
    return False


@st.composite
def _with_control(draw: st.DrawFn, valid: st.SearchStrategy[str]) -> str:
    """A valid text with a control character put in anywhere, or a newline at its end."""
    text = draw(valid)
    if draw(st.booleans()):
        return text + "\n"
    where = draw(st.integers(0, len(text)))
    control = draw(st.characters(categories=["Cc"]))
    return text[:where] + control + text[where:]


@pytest.mark.parametrize("field", sorted(CHECKS))
@given(data=st.data())
def test_a_text_with_a_control_character_or_a_trailing_newline_is_refused(
    field: str, data: st.DataObject
) -> None:
    check, valid = CHECKS[field]
    assert _refused(check, data.draw(_with_control(valid)))


@pytest.mark.parametrize("field", sorted(CHECKS))
@given(data=st.data())
def test_a_text_without_one_is_kept(field: str, data: st.DataObject) -> None:
    check, valid = CHECKS[field]
    assert not _refused(check, data.draw(valid))
