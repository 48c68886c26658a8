"""The station's configured regular expressions, read by a linear-time engine.

A plant configures how its labels read: ``serial_pattern`` and ``[label] pattern``
(``docs/station.md``). Each is matched against every line the operator scans, so a
pattern that backtracks (``^(P+)+$`` takes 1.6 s on 25 characters with Python's ``re``,
twice that for each more) would stall the station at a scan. These patterns are compiled
here, and only here, by RE2 (``google-re2``): its matching takes time linear in the text
whatever the pattern. What RE2 cannot match in linear time (backreferences such as
``\\1``, lookahead and lookbehind) it refuses to compile: :func:`compile_pattern` says why
in one line, and the configuration is refused at start-up.
"""

from typing import Any

import re2

#: RE2's own log of a refused pattern goes to the process' stderr, under the station's
#: one-line refusal; the refusal already names the problem.
_OPTIONS = re2.Options()
_OPTIONS.log_errors = False


def compile_pattern(pattern: str) -> Any:
    """``pattern`` compiled by RE2 (kept, so each pattern is compiled once); a
    :class:`ValueError` naming why RE2 refuses it."""
    try:
        return re2.compile(pattern, _OPTIONS)
    except re2.error as exc:
        (why,) = exc.args or ("refused",)
        why = why.decode("utf-8", "replace") if isinstance(why, bytes) else str(why)
        raise ValueError(f"not a regular expression the station reads (RE2): {why}") from None


def pattern_groups(pattern: str) -> frozenset[str]:
    """The named groups of ``pattern`` (a :class:`ValueError` if RE2 refuses it)."""
    return frozenset(compile_pattern(pattern).groupindex)


def full_match(pattern: str, text: str) -> dict[str, str] | None:
    """Whether ``pattern`` matches the whole of ``text``: its named groups that matched
    something (``{}`` without any), or None when it does not match."""
    match = compile_pattern(pattern).fullmatch(text)
    return None if match is None else {k: v for k, v in match.groupdict().items() if v}
