"""The operator's words for what the station's parts report.

Drivers, pyserial and the stillness detector speak to programmers ("device reports
readiness to read but returned no data", ``toe_up``, "link lost 5.2% of samples >
1.0%"). The screens speak to the operator: one short line that says what happened and
what to do, with the port named once. Each function here is that translation, in one
place, so every screen says the same thing the same way.
"""

import errno
from collections.abc import Callable

from rich.cells import cell_len, set_cell_size

from station.device import DeviceTimeoutError, NoReplyError
from station.domain.i18n import tr
from station.domain.patterns import full_match
from station.domain.signals.poses import Pose
from station.run.acquisition import StillnessThresholds, WindowVerdict

#: Longest explanation taken over from an error the station does not know, in terminal
#: cells (a Korean or Chinese character takes two).
MAX_UNKNOWN = 80

_ERRNO_WORDS: dict[int, Callable[[], str]] = {
    errno.ENOENT: lambda: tr("no such port: is the unit's cable plugged in?"),
    errno.ENODEV: lambda: tr("no such port: is the unit's cable plugged in?"),
    errno.ENXIO: lambda: tr("no such port: is the unit's cable plugged in?"),
    errno.EACCES: lambda: tr("permission denied (the station's user needs access to serial ports)"),
    errno.EPERM: lambda: tr("permission denied (the station's user needs access to serial ports)"),
    errno.EBUSY: lambda: tr("the port is in use by another program"),
    errno.EIO: lambda: tr("the cable was pulled"),
}
_PULLED = ("readiness to read but returned no data", "disconnected", "Input/output error")


def _pose_names() -> dict[str, str]:
    """Every named pose (station.domain.signals.poses) as the operator says it, in their
    language."""
    return {
        "shaft_up": tr("shaft up"),
        "shaft_down": tr("shaft down"),
        "toe_up": tr("toe up"),
        "toe_down": tr("toe down"),
        "face_up": tr("face up"),
        "face_down": tr("face down"),
        "verify_tilted": tr("verify tilted"),
        "toe_face_head_up": tr("toe face head up"),
        "toe_back_grip_up": tr("toe back grip up"),
        "toe_back_head_up": tr("toe back head up"),
        "heel_face_grip_up": tr("heel face grip up"),
        "heel_face_head_up": tr("heel face head up"),
        "heel_back_grip_up": tr("heel back grip up"),
    }


def said_of(subject: str, said: str) -> str:
    """``subject: said`` with the colon of the operator's language (full width in
    Chinese)."""
    return tr("{subject}: {said}", subject=subject, said=said)


def pose_words(name: str) -> str:
    """A pose as the operator says it: ``toe_up`` → ``toe up`` (translated)."""
    return _pose_names().get(name) or name.replace("_", " ")


def pose_instruction(asked: Pose) -> str:
    """What the operator does to put the putter in ``asked``, in their language."""
    said = {
        "shaft_up": tr("stand the putter on its head, shaft pointing up"),
        "shaft_down": tr("hold the putter upside down, grip on the floor"),
        "toe_up": tr("lay the putter on its heel, toe pointing up"),
        "toe_down": tr("rest the putter on its toe, heel pointing up"),
        "face_up": tr("lay the putter on its back, face pointing up"),
        "face_down": tr("lay the putter face down"),
        "verify_tilted": tr("put the putter in the tilted verification cradle"),
    }.get(asked.name)
    if said is not None:
        return said
    if asked.instruction.startswith("put the putter in the corner cradle"):
        return tr("put the putter in the corner cradle: {pose}", pose=pose_words(asked.name))
    return asked.instruction


def verdict_word(verdict: str) -> str:
    """``pass``/``fail`` as the operator reads it: ``PASS``, ``FAIL`` (translated)."""
    return {"pass": tr("PASS"), "fail": tr("FAIL")}.get(verdict, verdict.upper())


def disposition_word(disposition: str) -> str:
    """Where a judged unit goes, in one word: ``ship``, ``retest``, ``rework`` (translated)."""
    return {"ship": tr("ship"), "retest": tr("retest"), "rework": tr("rework")}.get(
        disposition, disposition
    )


def not_a_serial(text: str, pattern: str) -> str | None:
    """Why ``text`` scanned at a prompt is refused as a serial number (None: it is one)."""
    if full_match(pattern, text) is not None:
        return None
    return tr(
        "{text} is not a serial number (expected {pattern})", text=repr(text), pattern=pattern
    )


def not_a_label(text: str, pattern: str) -> str:
    """A scanned line the station's label pattern does not read."""
    return tr(
        "{text} is not a label this station reads (expected {pattern})",
        text=repr(text),
        pattern=pattern,
    )


def other_product(serial: str, part_number: str, ours: str) -> str:
    """A unit of another product than the station calibrates."""
    return tr(
        "{serial} is a {part_number}; this station calibrates {ours}: set it aside, "
        "nothing was recorded",
        serial=serial,
        part_number=part_number,
        ours=ours,
    )


def wrong_unit(reported: str, expected: str) -> str:
    """Another unit came back on the cable than the one being calibrated."""
    return tr(
        "{reported} plugged in, {expected} expected: plug {expected} back in, or abort",
        reported=reported,
        expected=expected,
    )


def serial_mismatch(label: str, reported: str) -> str:
    """The unit on the cable reports another serial number than the label scanned: the
    run stops before it starts."""
    return tr(
        "serial number mismatch: label says {label}, unit reports {reported}: "
        "set the unit aside; nothing was recorded",
        label=repr(label),
        reported=repr(reported),
    )


def _errno_of(exc: BaseException) -> int | None:
    seen: BaseException | None = exc
    while seen is not None:
        if isinstance(seen, OSError) and seen.errno in _ERRNO_WORDS:
            return seen.errno
        seen = seen.__cause__ or seen.__context__
    return None


def port_problem(exc: BaseException) -> str:
    """Why the unit's port failed, in a few words (the port itself is not repeated)."""
    code = _errno_of(exc)
    if code is not None:
        return _ERRNO_WORDS[code]()
    if isinstance(exc, NoReplyError):
        return tr("the unit does not answer: is it switched on and the right unit?")
    if isinstance(exc, DeviceTimeoutError):
        return tr("the unit stopped sending")
    text = str(exc)
    if any(marker in text for marker in _PULLED):
        return tr("the cable was pulled")
    first = (text.splitlines() or [type(exc).__name__])[0]
    if cell_len(first) <= MAX_UNKNOWN:
        return first
    return set_cell_size(first, MAX_UNKNOWN - 1).rstrip() + "…"


def capture_refused(verdict: WindowVerdict | None, limits: StillnessThresholds) -> str | None:
    """Why a window in which the unit lies still is not captured (None: it is not refused)."""
    if verdict is None or verdict.still or verdict.motion:
        return None
    if verdict.loss_fraction > limits.max_loss_fraction:
        return tr(
            "capture refused: the cable loses {lost} of the samples "
            "(at most {allowed}): check the cable and its plug",
            lost=f"{verdict.loss_fraction:.0%}",
            allowed=f"{limits.max_loss_fraction:.0%}",
        )
    if verdict.saturated_axes:
        return None  # the unit fails at once, with its own message
    return tr("capture refused: {reasons}", reasons="; ".join(verdict.reasons))


def moved_early() -> str:
    """The putter moved before its capture was done."""
    return tr("the putter moved: the capture starts again once it lies still")
