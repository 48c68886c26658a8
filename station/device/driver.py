"""The station's driver for a putter on a serial link.

:class:`PutterDriver` opens any pyserial URL (``/dev/ttyUSB0``, a pty path,
``socket://host:port``, ``loop://``) and reads it with pyserial's own
:class:`serial.threaded.ReaderThread`, whose protocol
(:class:`~station.device.link.PutterLink`) parses frames, accounts for the link's
health and fills bounded buffers with samples. Commands go one at a time, each
waiting for its reply. Nothing in it blocks longer than a command's reply timeout,
and :meth:`PutterDriver.drain` never waits (it parses what the port holds when the
reader rests, so the station's pass and the port share one wake), so an operator
interface can poll it from its own loop.
"""

import logging
import queue
import threading
import time
from typing import cast

import serial
from serial.threaded import ReaderThread

from station.device.buffer import SampleBuffer
from station.device.errors import (
    DeviceDisconnectedError,
    DeviceError,
    DeviceRejectedError,
    DeviceTimeoutError,
    NoReplyError,
    ProtocolError,
    SerialNumberMismatchError,
)
from station.device.link import PutterLink
from station.device.messages import DeviceCalibration, Identity
from station.device.ports import open_port
from station.device.protocol import (
    DEFAULT_BAUD,
    PROTOCOL_VERSION,
    RATE_STRUCT,
    ErrorCode,
    Frame,
    FrameType,
    StreamMode,
    decode_text,
    encode_frame,
)
from station.device.stats import LinkCounters
from station.domain.closing import Closing
from station.domain.constants import DEFAULT_RATE_HZ
from station.domain.sensors.sensor import ADC_MAX
from station.domain.signals.samples import SampleBlock

log = logging.getLogger(__name__)

#: Default capacity of each sample buffer: two minutes at the default rate.
DEFAULT_BUFFER_ROWS = 120 * DEFAULT_RATE_HZ
#: How often a command waiting for its reply looks whether the link has failed, s.
_FAILURE_POLL_S = 0.05


class PutterDriver(Closing):
    """A putter on a serial link.

    Open it with :meth:`open`; use it as a context manager or call :meth:`close`. It
    reads only what the unit sends once it is open: the port's input is flushed first
    (``reset_input_buffer``), and :meth:`start_stream` starts a fresh stream.
    Samples come out as :class:`~station.domain.signals.samples.SampleBlock`: ``seq`` is the
    unwrapped sequence number (counting from 0 at each :meth:`start_stream`, gaps
    preserved), ``accel`` in ADC counts (in g from :meth:`drain_calibrated`), ``gyro``
    in deg/s and ``temperature`` in °C.
    """

    def __init__(
        self,
        port: serial.SerialBase,
        *,
        reply_timeout: float = 0.5,
        retries: int = 1,
        buffer_rows: int = DEFAULT_BUFFER_ROWS,
        adc_max: int = ADC_MAX,
    ) -> None:
        self._name = str(port.port)
        self.reply_timeout = reply_timeout
        self.retries = retries
        self._rate_hz = DEFAULT_RATE_HZ
        self._link = PutterLink(self._name, buffer_rows, adc_max)
        self._command_lock = threading.Lock()
        # The stubs ask for serial.Serial; the thread needs only read, in_waiting,
        # cancel_read and write, and this reset_input_buffer, which every pyserial port has.
        tty = cast(serial.Serial, port)
        # What the unit sent before the port was opened (an earlier run's stream, left in
        # the port's buffer) is never read.
        tty.reset_input_buffer()
        self._reader = ReaderThread(tty, lambda: self._link)
        self._reader.name = "putter-reader"
        self._reader.start()
        self._reader.connect()

    @classmethod
    def open(
        cls,
        url: str,
        *,
        baudrate: int = DEFAULT_BAUD,
        read_timeout: float = 0.01,
        reply_timeout: float = 0.5,
        retries: int = 1,
        buffer_rows: int = DEFAULT_BUFFER_ROWS,
        adc_max: int = ADC_MAX,
    ) -> "PutterDriver":
        """Open the putter at ``url`` (any :func:`serial.serial_for_url` URL).

        ``read_timeout`` bounds how long the reader thread blocks in one read;
        ``reply_timeout`` is how long a command waits for its reply before it is sent
        again, ``retries`` times; ``adc_max``: the largest count the unit's accelerometer
        sends (its product's sensor's, :mod:`station.domain.sensors.sensor_spec`).
        """
        try:
            port = open_port(url, baudrate=baudrate, timeout=read_timeout)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise DeviceDisconnectedError(f"cannot open putter port {url}: {exc}") from exc
        return cls(
            port,
            reply_timeout=reply_timeout,
            retries=retries,
            buffer_rows=buffer_rows,
            adc_max=adc_max,
        )

    # -- lifetime ---------------------------------------------------------------------

    def close(self) -> None:
        """Stop the reader thread and close the port. Buffered samples stay drainable."""
        self._link.close()
        self._reader.close()

    @property
    def url(self) -> str:
        """The port this driver talks through."""
        return self._name

    @property
    def connected(self) -> bool:
        """False once the link has failed or the driver was closed."""
        return self._link.failure is None and not self._link.closing

    @property
    def failure(self) -> DeviceError | None:
        """Why the link ended, if it did (e.g. :class:`DeviceDisconnectedError`)."""
        return self._link.failure

    @property
    def rate_hz(self) -> int:
        """The sample rate last set (the unit starts at 500 samples/s)."""
        return self._rate_hz

    @property
    def stats(self) -> LinkCounters:
        """A snapshot of the link's counters."""
        return self._link.stats()

    # -- samples ----------------------------------------------------------------------

    def drain(self, max_rows: int | None = None) -> SampleBlock:
        """Take the raw samples received so far; never waits (what the port holds is read
        now, if the reader rests: :meth:`PutterLink.read_now`).

        Raises the link's failure (e.g. :class:`DeviceDisconnectedError`) only once every
        sample received before it has been handed out.
        """
        return self._take(self._link.raw, max_rows)

    def drain_calibrated(self, max_rows: int | None = None) -> SampleBlock:
        """As :meth:`drain`, for samples of the calibrated stream (acceleration in g)."""
        return self._take(self._link.calibrated, max_rows)

    def pending(self) -> int:
        """How many raw samples have arrived and wait to be drained (what the port holds is
        read now, if the reader rests, as :meth:`drain` reads it)."""
        self._link.read_now(self._reader.serial)
        return len(self._link.raw)

    def wait_samples(self, count: int, timeout: float, *, calibrated: bool = False) -> SampleBlock:
        """Block until ``count`` samples are buffered, then drain exactly ``count``.

        For scripts and tests; an interface loop should poll :meth:`drain` instead.
        Raises :class:`DeviceTimeoutError` (nothing is drained then) or the link's failure.
        """
        link = self._link
        buffer = link.calibrated if calibrated else link.raw
        with link.attended():
            arrived = buffer.wait(count, timeout, lambda: link.failure is not None)
        if not arrived:
            if link.failure is not None:
                raise link.failure
            raise DeviceTimeoutError(
                f"putter at {self._name}: {len(buffer)} of {count} samples after {timeout:g} s"
            )
        return buffer.drain(count)

    def _take(self, buffer: SampleBuffer, max_rows: int | None) -> SampleBlock:
        self._link.read_now(self._reader.serial)
        # Read the failure first: the reader stores its last samples before it fails, so
        # a failure seen here means the drain below holds everything received.
        failure = self._link.failure
        rows = buffer.drain(max_rows)
        if not len(rows) and failure is not None:
            raise failure
        return rows

    # -- commands ---------------------------------------------------------------------

    def identify(self, expected_serial: str | None = None) -> Identity:
        """Ask who the unit is; check its serial number against its label if given."""
        reply = self._command(FrameType.IDENTIFY, b"", FrameType.IDENTITY)
        try:
            identity = Identity.decode(reply.payload)
        except ValueError as exc:
            raise ProtocolError(f"putter at {self._name}: bad IDENTITY reply: {exc}") from exc
        if identity.protocol_version != PROTOCOL_VERSION:
            raise ProtocolError(
                f"putter at {self._name} speaks protocol version {identity.protocol_version}; "
                f"this station speaks version {PROTOCOL_VERSION}"
            )
        if expected_serial is not None and identity.serial != expected_serial:
            raise SerialNumberMismatchError(expected_serial, identity.serial)
        return identity

    def set_rate(self, rate_hz: int) -> None:
        """Set the stream's sample rate; the unit accepts 1 to 1000 samples/s.

        The unit is the judge of the range: it refuses others with
        :class:`DeviceRejectedError`.
        """
        if not 0 <= rate_hz <= 0xFFFF:
            raise ValueError(f"sample rate {rate_hz} does not fit the 16-bit field")
        self._command(FrameType.SET_RATE, RATE_STRUCT.pack(rate_hz), FrameType.ACK)
        self._rate_hz = rate_hz

    def start_stream(self, calibrated: bool = False) -> None:
        """Start a fresh stream of raw samples, or calibrated ones (the unit applies its
        calibration).

        The unit restarts its sequence numbers; so does the driver's count. Only samples
        the unit sends after acknowledging the command are handed out: those held and not
        drained yet, and those of an earlier stream still on their way, are dropped
        (:meth:`PutterLink.restart_stream`).
        """
        mode = StreamMode.CALIBRATED if calibrated else StreamMode.RAW
        self._link.restart_stream()
        self._command(FrameType.START_STREAM, bytes((mode,)), FrameType.ACK)

    def stop_stream(self) -> None:
        """Stop the stream. Samples already buffered stay there."""
        self._command(FrameType.STOP_STREAM, b"", FrameType.ACK)

    def write_calibration(self, calibration: DeviceCalibration) -> None:
        """Store calibration coefficients in the unit (float32, see ``docs/protocol.md``)."""
        self._command(FrameType.WRITE_CAL, calibration.encode(), FrameType.ACK)

    def read_calibration(self) -> DeviceCalibration:
        """Read back the coefficients the unit holds."""
        reply = self._command(FrameType.READ_CAL, b"", FrameType.CALIBRATION)
        return DeviceCalibration.decode_reply(reply.payload)

    def write_gyro_calibration(self, calibration: DeviceCalibration) -> None:
        """Store the gyro coefficients (bias, K⁻¹) in the unit (the gyro extension)."""
        self._command(FrameType.WRITE_GYRO_CAL, calibration.encode(), FrameType.ACK)

    def read_gyro_calibration(self) -> DeviceCalibration:
        """Read back the gyro coefficients the unit holds (the gyro extension)."""
        reply = self._command(FrameType.READ_GYRO_CAL, b"", FrameType.GYRO_CALIBRATION)
        return DeviceCalibration.decode_reply(reply.payload)

    def _command(self, command: FrameType, payload: bytes, expect: FrameType) -> Frame:
        frame = encode_frame(command, payload)
        replies = self._link.replies
        # ReaderThread.write serialises writers; this lock pairs each command with its reply.
        with self._command_lock:
            while not replies.empty():
                replies.get_nowait()
            with self._link.attended():
                return self._send_awaiting(command, frame, expect)

    def _send_awaiting(self, command: FrameType, frame: bytes, expect: FrameType) -> Frame:
        """Send ``frame`` until its reply comes, up to :attr:`retries` more times."""
        for _ in range(self.retries + 1):
            self._check_alive()
            try:
                self._reader.write(frame)
            except (serial.SerialException, OSError) as exc:
                self._link.fail(
                    DeviceDisconnectedError(f"putter at {self._name}: write failed: {exc}")
                )
                self._check_alive()
            reply = self._await_reply(command, expect)
            if reply is not None:
                return reply
        self._check_alive()
        tries = self.retries + 1
        raise NoReplyError(
            f"putter at {self._name} did not answer {command.name} within "
            f"{self.reply_timeout:g} s ({tries} {'try' if tries == 1 else 'tries'})"
        )

    def _await_reply(self, command: FrameType, expect: FrameType) -> Frame | None:
        deadline = time.monotonic() + self.reply_timeout
        while (left := deadline - time.monotonic()) > 0:
            try:
                reply = self._link.replies.get(timeout=min(left, _FAILURE_POLL_S))
            except queue.Empty:
                if self._link.failure is not None:
                    return None
                continue
            if reply.type in (FrameType.ACK, FrameType.ERROR) and reply.payload[0] != command:
                log.debug("stale reply %s to 0x%02x ignored", reply.type, reply.payload[0])
                continue
            if reply.type == FrameType.ERROR:
                code = reply.payload[1]
                name = (
                    ErrorCode(code).name if code in ErrorCode._value2member_map_ else f"code {code}"
                )
                raise DeviceRejectedError(
                    f"putter at {self._name} refused {command.name}: {name}: "
                    f"{decode_text(reply.payload[2:])}",
                    code,
                )
            if reply.type != expect:
                raise ProtocolError(
                    f"putter at {self._name} answered {command.name} with "
                    f"{FrameType(reply.type).name}, expected {expect.name}"
                )
            return reply
        return None

    def _check_alive(self) -> None:
        if self._link.failure is not None:
            raise self._link.failure
        if self._link.closing:
            raise DeviceDisconnectedError(f"putter at {self._name}: driver is closed")
