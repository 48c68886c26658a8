"""The view model of a unit's run: what the unit screen shows, read at one instant.

:func:`station.loop.screens.unit_screen` draws a :class:`RunView` and nothing else, so the
screen does not depend on how the run or its journal keep their state, and a test can
draw any moment of a run without a unit.
"""

from dataclasses import dataclass

from station.domain.signals.poses import Pose
from station.run.acquisition import StillnessThresholds
from station.run.capture import LiveView
from station.run.messages import Message
from station.run.phases import Phase


@dataclass(frozen=True)
class RunView:
    """One moment of a unit's run, as the operator sees it."""

    serial: str
    phase: Phase
    #: Every pose of the run, in order (the fit poses, then the verification pose).
    poses: tuple[Pose, ...]
    #: The pose asked for now (``len(poses)`` once all are taken).
    index: int
    #: Indices of the poses taken.
    taken: frozenset[int]
    #: The unit while the pose is taken: sensed pose, stillness, the capture's share.
    live: LiveView
    #: The limits the stillness meters are drawn against.
    stillness: StillnessThresholds
    #: The latest messages, newest last.
    messages: tuple[Message, ...]
    #: Another unit plugged in while this one was awaited.
    wrong_unit: str | None

    @property
    def requested(self) -> Pose | None:
        """The pose asked for now (None once all are taken)."""
        return self.poses[self.index] if self.index < len(self.poses) else None
