""":func:`parse_toml`: any text is a table or one line naming the document."""

import tomllib

import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.domain.errors import InputError
from station.domain.toml_text import parse_toml


@given(st.text(alphabet=st.sampled_from('ab=[]{}"\n .#1e+-9_,'), max_size=60))
def test_any_text_is_the_readers_table_or_one_line_naming_the_document(text: str) -> None:
    try:
        expected = tomllib.loads(text)
    except ValueError:
        with pytest.raises(InputError) as info:
            parse_toml(text, "f.toml")
        assert str(info.value).startswith("f.toml: not valid TOML: ")
        assert "\n" not in str(info.value)
    else:
        assert parse_toml(text, "f.toml") == expected


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("x = " + "9" * 4301, "Exceeds the limit (4300 digits) for integer string conversion"),
        ("x = -" + "1" * 5000, "value has 5000 digits"),
        ("x = " + "[" * 900 + "]" * 900, "nested too deeply"),
        ("x = [", "Invalid value"),
    ],
    ids=["4301-digits", "negative-5000-digits", "nested-900-deep", "invalid"],
)
def test_what_the_reader_cannot_take_is_one_line(text: str, words: str) -> None:
    with pytest.raises(InputError) as info:
        parse_toml(text, "f.toml")
    assert words in str(info.value)
    assert "\n" not in str(info.value)
