"""The sentences a run says to the operator: the latest few, and a count of all.

The unit screen shows the latest (:data:`KEPT`); the station's log echoes every new one
(:meth:`MessageLog.since`). A message may name a ``topic`` (``link``) so that it can be
taken off the screen once the condition it is about ends.
"""

from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass

#: Messages kept for the screen.
KEPT = 6


@dataclass(frozen=True)
class Message:
    """A sentence for the operator; ``level`` is info, warn or error.

    ``topic`` names a condition the message is about (``link``): it is taken off the
    screen when the condition ends.
    """

    level: str
    text: str
    topic: str | None = None


class MessageLog:
    """The latest messages of one run (newest last) and how many were said in all."""

    def __init__(self) -> None:
        self._latest: deque[Message] = deque(maxlen=KEPT)
        #: Messages said so far (the log keeps only the latest).
        self.said = 0

    def say(self, level: str, text: str, topic: str | None = None) -> None:
        """Tell the operator something (newest last)."""
        self._latest.append(Message(level, text, topic))
        self.said += 1

    def unsay(self, topic: str) -> None:
        """Take the messages about ``topic`` off the screen: it is no longer true."""
        kept = [m for m in self._latest if m.topic != topic]
        self._latest.clear()
        self._latest.extend(kept)

    def since(self, seen: int) -> list[Message]:
        """The messages said after the first ``seen`` ones, as far as they are kept."""
        new = self.said - seen
        if new <= 0:
            return []
        return list(self._latest)[-min(new, len(self._latest)) :]

    def __iter__(self) -> Iterator[Message]:
        return iter(self._latest)

    def __len__(self) -> int:
        return len(self._latest)

    def __getitem__(self, index: int) -> Message:
        return self._latest[index]
