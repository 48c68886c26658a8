"""Reaching a unit again after its cable was pulled.

:class:`Reconnect` says the unit is lost, tries to open it again every
:data:`RECONNECT_EVERY_S`, names another unit plugged in instead (once per unit), and
takes the messages about the link off the screen when the right unit is back.
"""

import time
from collections.abc import Callable

from station.device import DeviceError, PutterDriver, SerialNumberMismatchError
from station.domain.i18n import tr
from station.run.messages import MessageLog
from station.run.operator_text import port_problem, wrong_unit

#: Wall-clock seconds between attempts to reach a unit whose cable was pulled.
RECONNECT_EVERY_S = 0.5


class Reconnect:
    """When to try the unit next, and which other unit was plugged in meanwhile."""

    def __init__(self, messages: MessageLog, reopen: Callable[[], PutterDriver]) -> None:
        self._messages = messages
        self._reopen = reopen
        self._next_attempt = 0.0
        #: The serial of another unit plugged in while this one was awaited.
        self.wrong_unit: str | None = None

    def lost(self, driver: PutterDriver, exc: DeviceError) -> None:
        """Say the unit is gone, close its link, and try again in a moment."""
        self._messages.say(
            "error",
            tr(
                "lost the unit ({problem}): plug it back in, the poses taken are kept",
                problem=port_problem(exc),
            ),
            topic="link",
        )
        driver.close()
        self._next_attempt = time.monotonic() + RECONNECT_EVERY_S

    def attempt(self) -> PutterDriver | None:
        """The unit's link again, once it is back (None: not yet, or not due)."""
        if time.monotonic() < self._next_attempt:
            return None
        self._next_attempt = time.monotonic() + RECONNECT_EVERY_S
        try:
            driver = self._reopen()
        except SerialNumberMismatchError as exc:
            if self.wrong_unit != exc.reported:
                self.wrong_unit = exc.reported
                self._messages.say("error", wrong_unit(exc.reported, exc.expected), topic="link")
            return None
        except DeviceError:
            return None
        self.wrong_unit = None
        self._messages.unsay("link")
        self._messages.say("info", tr("the unit is back: carry on"))
        return driver
