"""Why a pose could not be taken.

::

    CalstationError
    └── AcquisitionError        no trustworthy still window for this pose
        ├── NotStillError       the unit kept moving until the timeout
        ├── LinkQualityError    too many samples lost on the link
        └── SaturatedAxisError  an accelerometer axis sits at an ADC rail while still
"""

from station.domain.errors import CalstationError


class AcquisitionError(CalstationError):
    """No trustworthy still window could be taken for a pose."""

    def __init__(self, message: str, pose: str | None = None) -> None:
        super().__init__(f"pose {pose}: {message}" if pose else message)
        self.pose = pose


class NotStillError(AcquisitionError):
    """The unit never stayed still for a whole window before the timeout."""


class LinkQualityError(AcquisitionError):
    """The windows lost more samples on the link than the limit allows."""


class SaturatedAxisError(AcquisitionError):
    """An accelerometer axis sits at 0 or 4095 counts while the unit is still."""

    def __init__(self, message: str, axes: tuple[str, ...], pose: str | None = None) -> None:
        super().__init__(message, pose)
        self.axes = axes
