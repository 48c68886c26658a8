"""Errors of the link to the putter.

Every one of them is a :class:`station.domain.errors.CalstationError`, so the command line
prints its message as one line::

    CalstationError
    └── DeviceError                 anything about the putter on the wire
        ├── DeviceTimeoutError           an awaited stream of samples did not come in time
        │   └── NoReplyError             a command got no reply (after its retries)
        ├── ProtocolError           a reply that breaks the protocol
        │   └── DeviceRejectedError      the putter answered a command with an error reply
        ├── DeviceDisconnectedError      the port went away (cable pulled, server closed)
        └── SerialNumberMismatchError    the unit reports another serial number than its label

None of them discards samples already received: :meth:`PutterDriver.drain` hands
them out first and raises only once the buffer is empty.
"""

from station.domain.errors import CalstationError


class DeviceError(CalstationError):
    """Anything that went wrong with the putter on the wire."""


class DeviceTimeoutError(DeviceError):
    """Samples or a reply did not arrive within the deadline."""


class NoReplyError(DeviceTimeoutError):
    """A command got no reply within the reply timeout, retries included."""


class ProtocolError(DeviceError):
    """A frame arrived that the protocol does not allow at this point."""


class DeviceRejectedError(ProtocolError):
    """The putter answered a command with an error reply.

    ``code`` is the error code of the reply (see ``docs/protocol.md``).
    """

    def __init__(self, message: str, code: int) -> None:
        super().__init__(message)
        self.code = code


class DeviceDisconnectedError(DeviceError):
    """The port stopped working: cable pulled, pty closed or socket shut."""


class SerialNumberMismatchError(DeviceError):
    """The serial number the unit reports differs from the one on its label."""

    def __init__(self, expected: str, reported: str) -> None:
        super().__init__(
            f"serial number mismatch: label says {expected!r}, unit reports {reported!r}"
        )
        self.expected = expected
        self.reported = reported
