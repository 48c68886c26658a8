"""The phases of one unit's run and the moves allowed between them.

A run takes its poses (``POSE``: the fit poses, then the verification pose), solves
once the fit poses are in (``SOLVE``), writes the coefficients into the unit and reads
them back (``WRITE_BACK``), checks the unit's own calibrated output (``UNIT_OUTPUT``),
and ends with its verdict and record (``VERDICT``, then ``DONE``). A pulled cable sends
it to ``RECONNECT`` from wherever the unit was talked to; the unit's return sends it back
to its poses, or to the write-back when the poses were all taken. An abort or a failure
ends it from any phase but ``DONE``.

``SOLVE``, ``WRITE_BACK`` and ``VERDICT`` are passed through within one step of the
run: the interface sees ``POSE``, ``RECONNECT``, ``UNIT_OUTPUT`` and ``DONE``.
:func:`advance` refuses a move the table does not list, so a new step cannot slip in
unnoticed.
"""

from collections.abc import Mapping
from enum import StrEnum


class Phase(StrEnum):
    """Where the run stands."""

    POSE = "pose"
    SOLVE = "solve"
    WRITE_BACK = "write_back"
    UNIT_OUTPUT = "unit_output"
    RECONNECT = "reconnect"
    VERDICT = "verdict"
    DONE = "done"


#: The phases each phase may move to.
TRANSITIONS: Mapping[Phase, frozenset[Phase]] = {
    Phase.POSE: frozenset({Phase.SOLVE, Phase.WRITE_BACK, Phase.RECONNECT, Phase.VERDICT}),
    Phase.SOLVE: frozenset({Phase.POSE, Phase.VERDICT}),
    Phase.WRITE_BACK: frozenset({Phase.UNIT_OUTPUT, Phase.RECONNECT, Phase.VERDICT}),
    Phase.UNIT_OUTPUT: frozenset({Phase.RECONNECT, Phase.VERDICT}),
    Phase.RECONNECT: frozenset({Phase.POSE, Phase.WRITE_BACK, Phase.VERDICT}),
    Phase.VERDICT: frozenset({Phase.DONE}),
    Phase.DONE: frozenset(),
}

#: Phases in which a pose may still be taken again.
REDO_ALLOWED = frozenset({Phase.POSE, Phase.RECONNECT})


class PhaseError(RuntimeError):
    """A move between phases that :data:`TRANSITIONS` does not allow (a bug)."""


def advance(current: Phase, to: Phase) -> Phase:
    """``to``, if the run may move there from ``current``."""
    if to not in TRANSITIONS[current]:
        raise PhaseError(f"a run cannot go from {current} to {to}")
    return to
