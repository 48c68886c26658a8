"""Taking a pose again at the operator's word: when it may be, and the capture it
replaces kept in the journal for audit."""

from station.domain.poses import Pose
from station.results.journal import RunJournal
from station.run.operator_text import pose_words
from station.run.phases import REDO_ALLOWED, Phase
from station.run.record import replaced_capture


def redo_refusal(
    journal: RunJournal, poses: tuple[Pose, ...], index: int, phase: Phase
) -> str | None:
    """Why pose ``index`` cannot be taken again now (said to the operator), or None."""
    if index not in journal.captures:
        name = pose_words(poses[index].name)
        return f"pose {index + 1} ({name}) is not taken yet: nothing to redo"
    if phase not in REDO_ALLOWED:
        return "too late to redo a pose: the coefficients are being written"
    return None


def set_aside(journal: RunJournal, index: int) -> None:
    """Move pose ``index``'s capture to the journal's replaced captures."""
    capture = journal.captures.pop(index)
    replaced = replaced_capture(capture, "redone by the operator")
    journal.replaced.setdefault(index, []).append(replaced)


def latest_capture(journal: RunJournal) -> int | None:
    """The pose captured most recently, if any."""
    captures = journal.captures
    return max(captures, key=lambda i: captures[i].captured_at) if captures else None
