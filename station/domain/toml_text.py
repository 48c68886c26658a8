"""Reading a TOML document from a file, an upload or the shipped profiles: one place, one
kind of error.

Whatever the text, :func:`parse_toml` answers a table or an :class:`InputError` of one
line naming the document: invalid TOML, values nested deeper than the reader's recursion
goes (``x = [[[…]]]`` 900 deep), or an integer of more digits than Python converts
(4 300, ``sys.get_int_max_str_digits``: the reader's ``ValueError``, not a
``TOMLDecodeError``).
"""

import tomllib
from importlib import resources
from pathlib import Path
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


def read_text(path: Path, what: str) -> str:
    """The UTF-8 text of the file ``path``, or an :class:`InputError` of one line naming it
    and ``what`` it holds when it cannot be read or is not UTF-8 text."""
    try:
        return path.read_text(encoding="utf-8")
    except OSError as exc:
        raise InputError(f"{path}: cannot read the {what}: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not UTF-8 text") from None


def shipped_text(name: str) -> str:
    """The text of the shipped ``station/domain/profiles/<name>``."""
    return resources.files("station.domain.profiles").joinpath(name).read_text(encoding="utf-8")
