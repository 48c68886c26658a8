"""The putter on the wire: protocol, driver, link statistics and errors.

Public surface (everything else is private to the package)::

    driver = PutterDriver.open("socket://127.0.0.1:5000")
    driver.identify(expected_serial="PT000001")
    driver.start_stream()
    block = driver.drain()         # a SampleBlock: block.accel, block.gyro, block.summary()

The protocol itself is documented in ``docs/protocol.md``.
"""

from station.device.driver import PutterDriver
from station.device.errors import (
    DeviceDisconnectedError,
    DeviceError,
    DeviceRejectedError,
    DeviceTimeoutError,
    NoReplyError,
    ProtocolError,
    SerialNumberMismatchError,
)
from station.device.messages import DeviceCalibration, Identity
from station.device.protocol import DEFAULT_BAUD, PROTOCOL_VERSION
from station.device.stats import LinkCounters
from station.domain.constants import DEFAULT_RATE_HZ, MAX_RATE_HZ
from station.domain.signals.samples import SAMPLE_COLUMNS

__all__ = [
    "DEFAULT_BAUD",
    "DEFAULT_RATE_HZ",
    "MAX_RATE_HZ",
    "PROTOCOL_VERSION",
    "SAMPLE_COLUMNS",
    "DeviceCalibration",
    "DeviceDisconnectedError",
    "DeviceError",
    "DeviceRejectedError",
    "DeviceTimeoutError",
    "Identity",
    "LinkCounters",
    "NoReplyError",
    "ProtocolError",
    "PutterDriver",
    "SerialNumberMismatchError",
]
