"""The configured patterns (``serial_pattern``, ``[label] pattern``) are read by RE2:
a pattern that would backtrack for ever matches a scan at once, one RE2 cannot read is
refused in one line, and a label reads back the parts it was printed with."""

import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.domain.patterns import compile_pattern, full_match, pattern_groups
from station.domain.product.products import Label, LabelFormat
from station.run.operator_text import not_a_serial

#: Each of these backtracks exponentially in Python's ``re`` on its text (``^(P+)+$``:
#: 1.6 s at 25 characters, twice that for each more): at 200 characters no test would
#: end. RE2 answers in time linear in the text.
CATASTROPHIC = [
    (r"^(P+)+$", "P" * 200 + "x"),
    (r"(a|a)*b", "a" * 200),
    (r"^PT(\d+)+$", "PT" + "0" * 200 + "x"),
]


@pytest.mark.parametrize(("pattern", "text"), CATASTROPHIC)
def test_a_pattern_that_backtracks_answers_a_scan_at_once(pattern: str, text: str) -> None:
    refused = not_a_serial(text, pattern)
    assert refused is not None
    assert f"(expected {pattern})" in refused
    assert full_match(pattern, text[:-1] if text.endswith("x") else text + "b") is not None


@pytest.mark.parametrize(("pattern", "text"), CATASTROPHIC)
def test_a_label_form_that_backtracks_reads_a_scan_at_once(pattern: str, text: str) -> None:
    form = LabelFormat(pattern=f"(?P<serial>{pattern.strip('^$')})")
    assert form.read(text) is None


@pytest.mark.parametrize(
    ("pattern", "why"),
    [
        (r"^(P)\1$", r"invalid escape sequence: \1"),
        (r"^PT(?=\d)\d+$", "invalid perl operator: (?="),
        (r"^(?<!x)PT\d+$", "invalid perl operator: (?<!"),
        (r"^PT[\d+$", r"missing ]: [\d+$"),
    ],
)
def test_a_pattern_re2_cannot_read_is_refused_saying_why(pattern: str, why: str) -> None:
    with pytest.raises(ValueError, match="RE2") as info:
        compile_pattern(pattern)
    message = str(info.value)
    assert message.endswith(why)
    assert "\n" not in message
    with pytest.raises(ValueError, match="pattern is not a regular expression"):
        LabelFormat(pattern=f"(?P<serial>{pattern})")


def test_the_groups_of_a_pattern_are_its_named_groups() -> None:
    assert pattern_groups(r"(?P<serial>PT\d+)(/(?P<lot>L\w+))?") == {"serial", "lot"}
    assert pattern_groups(r"^PT\d{6}$") == frozenset()


parts = st.from_regex(r"[A-Z0-9]{1,8}", fullmatch=True)


@given(
    part=parts,
    revision=st.integers(0, 99),
    serial=st.from_regex(r"PT[0-9]{6}", fullmatch=True),
    lot=st.none() | parts,
)
def test_a_label_reads_back_the_parts_it_was_printed_with(
    part: str, revision: int, serial: str, lot: str | None
) -> None:
    form = LabelFormat(
        pattern=r"(?P<part_number>DIXX-[A-Z0-9]+)/(?P<revision>R\d+)/(?P<serial>PT\d{6})"
        r"(/(?P<lot>L\w+))?",
        prefix="]C1",
    )
    text = f"]C1DIXX-{part}/R{revision}/{serial}" + (f"/L{lot}" if lot else "")
    assert form.read(text) == Label(
        serial=serial,
        part_number=f"DIXX-{part}",
        revision=f"R{revision}",
        lot=f"L{lot}" if lot else None,
    )
    assert form.read(text + "/") is None  # the whole text, or nothing
