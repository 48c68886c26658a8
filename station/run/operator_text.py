"""The operator's words for what the station's parts report.

Drivers, pyserial and the stillness detector speak to programmers ("device reports
readiness to read but returned no data", ``toe_up``, "link lost 5.2% of samples >
1.0%"). The screens speak to the operator: one short line that says what happened and
what to do, with the port named once. Each function here is that translation, in one
place, so every screen says the same thing the same way.
"""

import errno
import re

from station.device import DeviceTimeoutError, NoReplyError
from station.run.acquisition import StillnessThresholds, WindowVerdict

#: Longest explanation taken over from an error the station does not know.
MAX_UNKNOWN = 80

_ERRNO_WORDS = {
    errno.ENOENT: "no such port: is the unit's cable plugged in?",
    errno.ENODEV: "no such port: is the unit's cable plugged in?",
    errno.ENXIO: "no such port: is the unit's cable plugged in?",
    errno.EACCES: "permission denied (the station's user needs access to serial ports)",
    errno.EPERM: "permission denied (the station's user needs access to serial ports)",
    errno.EBUSY: "the port is in use by another program",
    errno.EIO: "the cable was pulled",
}
_PULLED = ("readiness to read but returned no data", "disconnected", "Input/output error")


def pose_words(name: str) -> str:
    """A pose as the operator says it: ``toe_up`` → ``toe up``."""
    return name.replace("_", " ")


def not_a_serial(text: str, pattern: str) -> str | None:
    """Why ``text`` scanned at a prompt is refused as a serial number (None: it is one)."""
    if re.fullmatch(pattern, text):
        return None
    return f"{text!r} is not a serial number (expected {pattern})"


def not_a_label(text: str, pattern: str) -> str:
    """A scanned line the station's label pattern does not read."""
    return f"{text!r} is not a label this station reads (expected {pattern})"


def other_product(serial: str, part_number: str, ours: str) -> str:
    """A unit of another product than the station calibrates."""
    return (
        f"{serial} is a {part_number}; this station calibrates {ours}: set it aside, "
        "nothing was recorded"
    )


def wrong_unit(reported: str, expected: str) -> str:
    """Another unit came back on the cable than the one being calibrated."""
    return f"{reported} plugged in, {expected} expected: plug {expected} back in, or abort"


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
        return _ERRNO_WORDS[code]
    if isinstance(exc, NoReplyError):
        return "the unit does not answer: is it switched on and the right unit?"
    if isinstance(exc, DeviceTimeoutError):
        return "the unit stopped sending"
    text = str(exc)
    if any(marker in text for marker in _PULLED):
        return "the cable was pulled"
    first = (text.splitlines() or [type(exc).__name__])[0]
    return first if len(first) <= MAX_UNKNOWN else first[: MAX_UNKNOWN - 1] + "…"


def capture_refused(verdict: WindowVerdict | None, limits: StillnessThresholds) -> str | None:
    """Why a window in which the unit lies still is not captured (None: it is not refused)."""
    if verdict is None or verdict.still or verdict.motion:
        return None
    if verdict.loss_fraction > limits.max_loss_fraction:
        return (
            f"capture refused: the cable loses {verdict.loss_fraction:.0%} of the samples "
            f"(at most {limits.max_loss_fraction:.0%}): check the cable and its plug"
        )
    if verdict.saturated_axes:
        return None  # the unit fails at once, with its own message
    return "capture refused: " + "; ".join(verdict.reasons)


MOVED_EARLY = "the putter moved: the capture starts again once it lies still"
