"""Refusals of the calibration: the poses cannot give a trustworthy calibration.

Every refusal names its cause in one sentence and, where one pose is to blame, carries
that pose's index so a caller can point at it (a file line, a pose to redo)::

    CalibrationError
    ├── TooFewPosesError        fewer poses than the model has unknowns
    ├── InvalidValueError       NaN or infinity in a pose
    ├── RailValueError          a pose mean at an ADC rail (0 or 4095 counts): saturated
    ├── DuplicatePoseError      two poses closer than the minimum angle
    ├── CoplanarPosesError      the poses do not span three dimensions
    ├── IllConditionedError     the system's condition number is above the limit
    └── NonPositiveScaleError   k1, k2 or s_x² came out non-positive: no ellipsoid fits
"""

from station.errors import CalstationError


class CalibrationError(CalstationError):
    """The poses cannot give a trustworthy calibration.

    ``pose`` is the 0-based index of the pose to blame, or ``None`` when the set of
    poses as a whole is at fault.
    """

    def __init__(self, message: str, *, pose: int | None = None) -> None:
        super().__init__(message)
        self.pose = pose


class TooFewPosesError(CalibrationError):
    """Fewer poses than the model needs."""


class InvalidValueError(CalibrationError):
    """A pose holds NaN or infinity."""


class RailValueError(CalibrationError):
    """A pose mean sits at an ADC rail: the axis is saturated."""


class DuplicatePoseError(CalibrationError):
    """Two poses are closer together than the minimum angle."""


class CoplanarPosesError(CalibrationError):
    """The poses lie near one plane: some axis' offset or scale cannot be told."""


class IllConditionedError(CalibrationError):
    """The system's condition number exceeds the limit."""


class NonPositiveScaleError(CalibrationError):
    """The solution has a non-positive squared scale: no ellipsoid fits the poses."""
