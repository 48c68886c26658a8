"""The station's driver for a putter on a serial link.

:class:`PutterDriver` opens any pyserial URL (``/dev/ttyUSB0``, a pty path,
``socket://host:port``, ``loop://``), runs a reader thread that parses frames,
accounts for the link's health and fills a bounded buffer with samples, and sends
commands one at a time, waiting for their reply. Nothing in it blocks longer than a
command's reply timeout, and :meth:`PutterDriver.drain` never blocks at all, so an
operator interface can poll it from its own loop.
"""

import logging
import queue
import threading
import time

import numpy as np
import serial
from numpy.typing import NDArray

from station.closing import Closing
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
from station.device.messages import DeviceCalibration, Identity
from station.device.protocol import (
    DEFAULT_BAUD,
    DEFAULT_RATE_HZ,
    PROTOCOL_VERSION,
    RATE_STRUCT,
    SAMPLE_COLUMNS,
    ErrorCode,
    Frame,
    FrameParser,
    FrameType,
    StreamMode,
    decode_samples,
    decode_text,
    encode_frame,
)
from station.device.stats import LinkStats
from station.sensor import ADC_MAX

log = logging.getLogger(__name__)

SEQ_MODULUS = 1 << 16
#: Bytes asked for per read when the port cannot tell how many wait (sockets); the read
#: returns earlier when its timeout passes.
READ_CHUNK = 4096
#: Default capacity of each sample buffer: two minutes at the default rate.
DEFAULT_BUFFER_ROWS = 120 * DEFAULT_RATE_HZ


class _SequenceTracker:
    """Unwraps the 16-bit sequence numbers and counts the samples that went missing."""

    def __init__(self) -> None:
        self.last: int | None = None
        self.lost = 0
        self.gaps = 0

    def restart(self) -> None:
        """The unit restarts counting at 0: a first sample numbered 3 means 3 lost."""
        self.last = -1

    def unwrap(self, seq16: NDArray[np.float64]) -> NDArray[np.float64]:
        """Replace 16-bit sequence numbers by a running count; account for gaps.

        A step of d > 1 means d − 1 samples were lost; a step of 0 (a repeated frame)
        cannot happen on a working link and is kept as a gap-free step of 1.
        """
        values = seq16.astype(np.int64)
        start = values[0] if self.last is None else self.last
        previous = np.concatenate(([start % SEQ_MODULUS], values[:-1] % SEQ_MODULUS))
        steps = (values - previous) % SEQ_MODULUS
        if self.last is None:
            steps[0] = 0
        else:
            steps[steps == 0] = 1
        missing = steps[steps > 1] - 1
        self.lost += int(missing.sum())
        self.gaps += len(missing)
        base = values[0] if self.last is None else self.last
        unwrapped = base + np.cumsum(steps)
        self.last = int(unwrapped[-1])
        return unwrapped.astype(np.float64)


class PutterDriver(Closing):
    """A putter on a serial link.

    Open it with :meth:`open`; use it as a context manager or call :meth:`close`.
    Sample blocks are N-by-8 float64 arrays with columns
    :data:`~station.device.protocol.SAMPLE_COLUMNS`: the unwrapped sequence number
    (counting from 0 at each :meth:`start_stream`, gaps preserved), accelerometer
    x, y, z in ADC counts (in g from :meth:`drain_calibrated`), gyro x, y, z in deg/s
    and temperature in °C.
    """

    def __init__(
        self,
        port: serial.Serial,
        *,
        reply_timeout: float = 0.5,
        retries: int = 1,
        buffer_rows: int = DEFAULT_BUFFER_ROWS,
    ) -> None:
        self._port = port
        self._name = str(port.port)
        self.reply_timeout = reply_timeout
        self.retries = retries
        self._parser = FrameParser()
        self._raw = SampleBuffer(buffer_rows, len(SAMPLE_COLUMNS))
        self._calibrated = SampleBuffer(buffer_rows, len(SAMPLE_COLUMNS))
        self._seq = _SequenceTracker()
        self._samples = 0
        self._replies: queue.Queue[Frame] = queue.Queue()
        self._command_lock = threading.Lock()
        self._stats_lock = threading.Lock()
        self._failure: DeviceError | None = None
        self._stop = threading.Event()
        self._rate_hz = DEFAULT_RATE_HZ
        self._reader = threading.Thread(target=self._read_loop, name="putter-reader", daemon=True)
        self._reader.start()

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
    ) -> "PutterDriver":
        """Open the putter at ``url`` (any :func:`serial.serial_for_url` URL).

        ``read_timeout`` bounds how long the reader thread blocks in one read (and so
        how fast :meth:`close` returns); ``reply_timeout`` is how long a command waits
        for its reply before it is sent again, ``retries`` times.
        """
        try:
            port = serial.serial_for_url(url, baudrate=baudrate, timeout=read_timeout)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise DeviceDisconnectedError(f"cannot open putter port {url}: {exc}") from exc
        return cls(port, reply_timeout=reply_timeout, retries=retries, buffer_rows=buffer_rows)

    # -- lifetime ---------------------------------------------------------------------

    def close(self) -> None:
        """Stop the reader thread and close the port. Buffered samples stay drainable."""
        self._stop.set()
        self._reader.join(timeout=2.0)
        self._port.close()

    @property
    def url(self) -> str:
        """The port this driver talks through."""
        return self._name

    @property
    def connected(self) -> bool:
        """False once the link has failed or the driver was closed."""
        return self._failure is None and not self._stop.is_set()

    @property
    def failure(self) -> DeviceError | None:
        """Why the link ended, if it did (e.g. :class:`DeviceDisconnectedError`)."""
        return self._failure

    @property
    def rate_hz(self) -> int:
        """The sample rate last set (the unit starts at 500 samples/s)."""
        return self._rate_hz

    @property
    def stats(self) -> LinkStats:
        """A snapshot of the link's counters."""
        parser = self._parser
        with self._stats_lock:
            return LinkStats(
                samples=self._samples,
                samples_lost=self._seq.lost,
                seq_gaps=self._seq.gaps,
                crc_failures=parser.crc_failures,
                bad_headers=parser.bad_headers,
                resyncs=parser.resyncs,
                bytes_discarded=parser.bytes_discarded,
                buffer_overruns=self._raw.overruns + self._calibrated.overruns,
            )

    # -- samples ----------------------------------------------------------------------

    def drain(self, max_rows: int | None = None) -> NDArray[np.float64]:
        """Take the raw samples received so far (N-by-8); never blocks.

        Raises the link's failure (e.g. :class:`DeviceDisconnectedError`) only once every
        sample received before it has been handed out.
        """
        return self._take(self._raw, max_rows)

    def drain_calibrated(self, max_rows: int | None = None) -> NDArray[np.float64]:
        """As :meth:`drain`, for samples of the calibrated stream (acceleration in g)."""
        return self._take(self._calibrated, max_rows)

    def pending(self) -> int:
        """How many raw samples wait in the buffer."""
        return len(self._raw)

    def wait_samples(
        self, count: int, timeout: float, *, calibrated: bool = False
    ) -> NDArray[np.float64]:
        """Block until ``count`` samples are buffered, then drain exactly ``count``.

        For scripts and tests; an interface loop should poll :meth:`drain` instead.
        Raises :class:`DeviceTimeoutError` (nothing is drained then) or the link's failure.
        """
        buffer = self._calibrated if calibrated else self._raw
        if not buffer.wait(count, timeout, lambda: self._failure is not None):
            if self._failure is not None:
                raise self._failure
            raise DeviceTimeoutError(
                f"putter at {self._name}: {len(buffer)} of {count} samples after {timeout:g} s"
            )
        return buffer.drain(count)

    def _take(self, buffer: SampleBuffer, max_rows: int | None) -> NDArray[np.float64]:
        # Read the failure first: the reader stores its last samples before it fails, so
        # a failure seen here means the drain below holds everything received.
        failure = self._failure
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
        """Start streaming raw samples, or calibrated ones (the unit applies its calibration).

        The unit restarts its sequence numbers; so does the driver's count.
        """
        mode = StreamMode.CALIBRATED if calibrated else StreamMode.RAW
        with self._stats_lock:
            self._seq.restart()
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

    def _command(self, command: FrameType, payload: bytes, expect: FrameType) -> Frame:
        frame = encode_frame(command, payload)
        with self._command_lock:
            while not self._replies.empty():
                self._replies.get_nowait()
            for _ in range(self.retries + 1):
                self._check_alive()
                try:
                    self._port.write(frame)
                except (serial.SerialException, OSError) as exc:
                    self._fail(
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
                reply = self._replies.get(timeout=min(left, 0.05))
            except queue.Empty:
                if self._failure is not None:
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
        if self._failure is not None:
            raise self._failure
        if self._stop.is_set():
            raise DeviceDisconnectedError(f"putter at {self._name}: driver is closed")

    # -- reader thread ----------------------------------------------------------------

    def _fail(self, failure: DeviceError) -> None:
        if self._failure is None:
            self._failure = failure
            # Not a warning: the error reaches the station, which tells the operator in
            # plain words; Python's last-resort handler would print this raw text over
            # the screen and leave it there.
            log.info("%s", failure)
        self._raw.wake()
        self._calibrated.wake()

    def _read_loop(self) -> None:
        port = self._port
        try:
            while not self._stop.is_set():
                waiting = port.in_waiting
                data = port.read(waiting if waiting > 1 else READ_CHUNK)
                if data:
                    with self._stats_lock:
                        frames = self._parser.feed(data)
                    self._dispatch(frames)
        except (serial.SerialException, OSError) as exc:
            if not self._stop.is_set():
                self._fail(DeviceDisconnectedError(f"putter at {self._name} disconnected: {exc}"))
        except Exception as exc:  # a bug must not leave the station waiting forever
            self._fail(ProtocolError(f"putter at {self._name}: reader stopped: {exc!r}"))
            raise

    def _dispatch(self, frames: list[Frame]) -> None:
        raw = [f.payload for f in frames if f.type == FrameType.SAMPLE]
        calibrated = [f.payload for f in frames if f.type == FrameType.CAL_SAMPLE]
        if raw:
            self._store(decode_samples(raw), self._raw, check_range=True)
        if calibrated:
            self._store(decode_samples(calibrated, calibrated=True), self._calibrated)
        for frame in frames:
            if frame.type not in (FrameType.SAMPLE, FrameType.CAL_SAMPLE):
                self._replies.put(frame)

    def _store(
        self, block: NDArray[np.float64], buffer: SampleBuffer, check_range: bool = False
    ) -> None:
        if check_range:
            block = block[(block[:, 1:4] <= ADC_MAX).all(axis=1)]
            if not len(block):
                return
        with self._stats_lock:
            block[:, 0] = self._seq.unwrap(block[:, 0])
            self._samples += len(block)
        buffer.append(block)
