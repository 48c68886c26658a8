"""The station's error tree.

Every error meant for a person (bad input, a refused calibration, a device that does
not answer) derives from :class:`CalstationError`; the command-line interface prints
its message as one line and exits with status 2, never a traceback::

    CalstationError
    ├── InputError            a file, field or value the user gave is unusable
    └── calibration.CalibrationError   the poses cannot give a trustworthy calibration
"""


class CalstationError(Exception):
    """Base of every error whose message is shown to the operator as it is."""


class InputError(CalstationError):
    """A file, a field or a value given by the user is unusable."""
