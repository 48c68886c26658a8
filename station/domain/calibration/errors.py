"""Refusals of the calibration: the poses cannot give a trustworthy calibration.

Every refusal names its cause in one sentence and, where one pose is to blame, carries
that pose's index so a caller can point at it (a file line, a pose to redo)::

    CalibrationError
    ├── TooFewPosesError        fewer poses than the model has unknowns
    ├── InvalidValueError       NaN or infinity in a pose
    ├── NotCountsError          the values are acceleration (g, m/s²), not ADC counts
    ├── RailValueError          a pose mean at an ADC rail (0 or 4095 counts): saturated
    ├── BeyondDatasheetError    an axis reads further from 2048 than any KXM52 at 1 g
    ├── DuplicatePoseError      two poses closer than the minimum angle (eq. 10 only)
    ├── CoplanarPosesError      the poses do not span three dimensions
    ├── IllConditionedError     the geometry does not determine the model
    ├── NonPositiveScaleError   k1, k2 or s_x² came out non-positive: no ellipsoid fits
    └── InconsistentPosesError  the residuals exceed the limit and no single pose explains it
"""

from station.domain.errors import CalstationError


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


class NotCountsError(CalibrationError):
    """Every value is small: acceleration in g or m/s², not ADC counts."""


class BeyondDatasheetError(CalibrationError):
    """An axis reads further from the nominal offset than the datasheet allows at 1 g."""


class InconsistentPosesError(CalibrationError):
    """The poses do not fit one ellipsoid within the residual limit.

    ``pose`` is set only when the evidence singles one pose out; ``candidates`` lists
    the poses (0-based) that could each alone explain the misfit, when the evidence
    narrows it down to a few.
    """

    def __init__(
        self, message: str, *, pose: int | None = None, candidates: tuple[int, ...] = ()
    ) -> None:
        super().__init__(message, pose=pose)
        self.candidates = candidates


class DuplicatePoseError(CalibrationError):
    """Two poses are closer together than the minimum angle."""


class CoplanarPosesError(CalibrationError):
    """The poses lie near one plane: some axis' offset or scale cannot be told."""


class IllConditionedError(CalibrationError):
    """The system's condition number exceeds the limit."""


class NonPositiveScaleError(CalibrationError):
    """The solution has a non-positive squared scale: no ellipsoid fits the poses."""
