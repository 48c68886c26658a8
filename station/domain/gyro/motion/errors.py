"""Why a gyro matrix or a recorded stream cannot be fitted.

Errors::

    station.domain.errors.CalstationError
    ├── GyroMatrixError     errors.py   the moves cannot determine K (too few, all in one axis)
    └── StreamError         errors.py   a recorded stream that cannot be calibrated
"""

from station.domain.errors import CalstationError


class GyroMatrixError(CalstationError):
    """The moves cannot determine the gyro matrix: too few usable, or too alike."""


class StreamError(CalstationError):
    """A recorded stream that cannot be calibrated: malformed, or too few still poses."""
