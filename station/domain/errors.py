"""The root of every error tree in calstation.

Every error meant for a person (bad input, a refused calibration, a device that does
not answer) derives from :class:`CalstationError`; the command-line interface prints
its message as one line and exits with status 2, never a traceback. Each package keeps
its own branch, drawn in full where it is defined; the station's::

    CalstationError
    ├── InputError                          a file, field or value the user gave is unusable
    ├── calibration.CalibrationError        the poses cannot give a trustworthy calibration
    │   └── TooFewPosesError, …             station/domain/calibration/errors.py
    ├── gyro.NotIdentifiableError           the log cannot separate the terms asked for
    ├── device.DeviceError                  the putter on the wire
    │   └── DeviceTimeoutError, …           station/device/errors.py
    ├── acquisition.AcquisitionError        no trustworthy still window for a pose
    │   └── NotStillError, …                station/run/acquisition/errors.py
    ├── storage.StoreError                  a run record could not be stored
    │   └── StoreUnavailableError, …        station/results/storage.py
    └── outbox_files.UnreadableRecordError  an outbox file that is not a run record

The results database (:mod:`db`) and the server (:mod:`api`) derive their own from the
same root and draw them in their ``__init__``. The station's loop sees the database's
only as :class:`station.results.storage.StoreError`: storage translates them. Not in the tree,
because no person should ever read them: ``run.phases.PhaseError`` (a ``RuntimeError``,
a bug in the run's state machine).
"""

from pydantic import ValidationError

from station.domain.constants import PATTERN_WORDS


class CalstationError(Exception):
    """Base of every error whose message is shown to the operator as it is."""


class InputError(CalstationError):
    """A file, a field or a value given by the user is unusable."""


def validation_problem(exc: ValidationError, *, env_prefix: str | None = None) -> str:
    """The first problem pydantic found, as ``field.sub: message`` (a person reads it).

    A validator's own sentence is given as it is, without pydantic's "Value error, "; a
    value refused by a pattern is said with what such a value is (``PATTERN_WORDS``), not
    the regular expression.
    With ``env_prefix`` the field is named as its environment variable
    (``CALSTATION_DATABASE_URL``), for settings read from the environment.
    """
    first = exc.errors(include_url=False)[0]
    pattern = first.get("ctx", {}).get("pattern")
    if first["type"] == "string_pattern_mismatch" and pattern in PATTERN_WORDS:
        first["msg"] = f"{first['input']!r} is refused: {PATTERN_WORDS[pattern]}"
    parts = [str(part) for part in first["loc"]]
    if env_prefix is not None and parts:
        parts[0] = env_prefix + parts[0].upper()
    field = ".".join(parts)
    error = first.get("ctx", {}).get("error")
    message = str(error) if first["type"] == "value_error" and error is not None else first["msg"]
    return f"{field}: {message}" if field else message
