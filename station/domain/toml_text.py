"""Reading a TOML document from a file or an upload: one place, one kind of error.

Whatever the text, :func:`parse_toml` answers a table or an :class:`InputError` of one
line naming the document: invalid TOML, values nested deeper than the reader's recursion
goes (``x = [[[…]]]`` 900 deep), or an integer of more digits than Python converts
(4 300, ``sys.get_int_max_str_digits``: the reader's ``ValueError``, not a
``TOMLDecodeError``).
"""

import tomllib
from typing import Any

from station.domain.errors import InputError


def parse_toml(text: str, shown: str) -> dict[str, Any]:
    """The table of the TOML ``text`` (``shown``: its name in the error)."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{shown}: not valid TOML: {exc}") from None
    except RecursionError:
        raise InputError(f"{shown}: not valid TOML: its values are nested too deeply") from None
    except ValueError as exc:  # int(): more digits than sys.get_int_max_str_digits()
        reason = str(exc).split(";")[0]
        raise InputError(f"{shown}: not valid TOML: {reason}") from None
