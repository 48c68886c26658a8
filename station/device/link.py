"""The station's side of the wire, as a :class:`serial.threaded.Protocol`.

pyserial's :class:`~serial.threaded.ReaderThread` reads the port and hands every
chunk to :meth:`PutterLink.data_received`; the link cuts it into frames with the
:class:`~station.device.protocol.FrameParser` (the putter's frames carry a length
and a CRC, not the terminator pyserial's ``Packetizer`` splits on), unwraps the
samples' sequence numbers into the two sample buffers and queues every other frame
as a reply for the command waiting on it. When the thread ends,
:meth:`connection_lost` records why, so that nobody waits for a dead link.

**One wake for the station's pass and the port.** At the putter's own rate
the reader rests after each chunk, and the station's loop reads what waits at the port
itself when it drains the samples (:meth:`PutterLink.read_now`, from
:meth:`station.device.driver.PutterDriver.drain`): the pass that looks at the samples
is the one that parses them, with its caches warm, instead of a second thread woken for
it (each wake cost about half a millisecond whatever it carried, some 30 times a
frame's parsing). The reader stays the port's safety net: it reads at once while a
command waits for its reply or a script waits for samples (:meth:`PutterLink.attended`),
on a stream faster than the putter's own, and whenever the station has not read for
:data:`REST_S`, so the port's buffer never fills (nor a failure goes unseen) while the
loop is busy elsewhere.
"""

import contextlib
import logging
import queue
import threading
import time
from collections.abc import Iterator

import serial
from serial.threaded import Protocol

from station.device.buffer import SampleBuffer
from station.device.errors import DeviceDisconnectedError, DeviceError, ProtocolError
from station.device.protocol import Frame, FrameParser, FrameType, decode_samples
from station.device.sequence import SequenceTracker
from station.device.stats import LinkCounters
from station.domain.sensors.sensor import ADC_MAX
from station.domain.signals.samples import SampleBlock

log = logging.getLogger(__name__)

#: A read smaller than this (bytes) drained the port: the reader rests after it. A tty
#: hands out at most its line discipline's 4 KiB buffer a read, so a read this big may
#: have left more behind, and the port is read again at once.
PACE_BELOW_BYTES = 3072
#: The longest the reader rests while nobody reads the port (s). At the putter's 10 kB/s
#: a second is 10 kB: within a pty's 20 kB and a USB serial port's 64 kB of buffer, and
#: the longest a pulled cable goes unnoticed by a station that does not read.
REST_S = 1.0
#: A stream faster than this (bytes a second: three times the putter's own 10 kB/s, so
#: above its raw and calibrated streams at once) is a sped-up simulator's, and is read as
#: it comes, never paced: a read drains at most what the port's buffer holds (4 kB on a
#: pty), so one read a rest would fall behind it and the putter would drop what it cannot
#: send. Judged over :data:`RATE_WINDOW_S`; a new link starts paced.
UNPACED_ABOVE_BYTES_PER_S = 30_000
RATE_WINDOW_S = 0.5


class PutterLink(Protocol):
    """Frames in, samples and replies out; the link's counters and its failure.

    ``name`` is the port, for messages; ``buffer_rows`` the capacity of each of the
    raw and calibrated sample buffers; ``adc_max`` the largest count the unit's
    accelerometer sends (a raw sample beyond it is corrupt and dropped).
    """

    def __init__(self, name: str, buffer_rows: int, adc_max: int = ADC_MAX) -> None:
        self.name = name
        self.adc_max = adc_max
        self.raw = SampleBuffer(buffer_rows)
        self.calibrated = SampleBuffer(buffer_rows)
        self.replies: queue.Queue[Frame] = queue.Queue()
        self.closing = False
        self._parser = FrameParser()
        self._seq = SequenceTracker()
        #: A START_STREAM was sent and its ACK is not in yet: every sample received until
        #: then is of an earlier stream (:meth:`restart_stream`).
        self._starting = False
        self._samples = 0
        self._lock = threading.Lock()
        self._failure: DeviceError | None = None
        #: How many wait on the port (a command for its reply, a script for samples): the
        #: reader does not rest while any does.
        self._attending = 0
        #: Ends the reader's rest: someone waits on the port, the link closes, the station's
        #: read met a failure or a stream too fast for its passes.
        self._wake = threading.Event()
        #: Held by whoever reads the port: the reader, or the station while the reader rests.
        self._port_lock = threading.Lock()
        self._resting = False
        self._read_at = time.monotonic()
        self._paced = True
        self._rate_since: float | None = None
        self._rate_bytes = 0

    @property
    def failure(self) -> DeviceError | None:
        """Why the link ended, if it did."""
        return self._failure

    def stats(self) -> LinkCounters:
        """A snapshot of the link's counters."""
        parser = self._parser
        with self._lock:
            return LinkCounters(
                samples=self._samples,
                lost_samples=self._seq.lost,
                gaps=self._seq.gaps,
                crc_errors=parser.crc_errors,
                bad_headers=parser.bad_headers,
                resyncs=parser.resyncs,
                bytes_discarded=parser.bytes_discarded,
                buffer_overruns=self.raw.overruns + self.calibrated.overruns,
            )

    @contextlib.contextmanager
    def attended(self) -> Iterator[None]:
        """While inside, someone waits on the port (a command for its reply, a script for
        samples): the reader reads as data comes, never resting."""
        with self._lock:
            self._attending += 1
        self._wake.set()
        try:
            yield
        finally:
            with self._lock:
                self._attending -= 1

    def close(self) -> None:
        """The driver closes the link: a resting reader ends its rest."""
        self.closing = True
        self._wake.set()

    def read_now(self, port: serial.Serial) -> None:
        """Read and parse what waits at ``port``, in the caller's thread, if the reader
        rests (else it reads the port itself, and nothing is done). A port that fails
        here ends the reader's rest: its own read meets the failure and ends the link; a
        port that holds nothing lets the rest run out (:data:`REST_S`), so the reader
        reads it then, and meets a peer that went away."""
        if not self._port_lock.acquire(blocking=False):
            return
        try:
            if not self._resting:
                return
            while size := port.in_waiting:
                data = port.read(size)
                self._received(data)
                # Only a read that took bytes relieves the reader: a socket whose peer is
                # gone holds none and raises nothing here, and only the reader's own read
                # meets its end.
                self._read_at = time.monotonic()
                if len(data) < PACE_BELOW_BYTES:
                    break
            if not self._paced:
                self._wake.set()
        except (serial.SerialException, OSError):
            self._wake.set()
        except Exception as exc:  # a bug must not pass unseen, nor leave the reader resting
            log.error("putter read failed", exc_info=exc)
            self.fail(ProtocolError(f"putter at {self.name}: read failed: {exc!r}"))
            self._wake.set()
        finally:
            self._port_lock.release()

    def restart_stream(self) -> None:
        """A START_STREAM is about to be sent: the unit counts its samples from 0 again
        once it acknowledges it, and nothing received before that ACK is of the new
        stream. Every sample until the ACK is dropped (an earlier stream's, still in the
        port's or the unit's buffers, or sent while the command was on its way), and at
        the ACK the samples held and not yet drained go too (:meth:`_received`)."""
        self._starting = True

    def fail(self, failure: DeviceError) -> None:
        """Record the first failure and wake everyone waiting for samples."""
        if self._failure is None:
            self._failure = failure
            # Not a warning: the error reaches the station, which tells the operator in
            # plain words; Python's last-resort handler would print this raw text over
            # the screen and leave it there.
            log.info("%s", failure)
        self.raw.wake()
        self.calibrated.wake()

    # -- serial.threaded.Protocol ---------------------------------------------------

    def data_received(self, data: bytes) -> None:
        """Parse a chunk the reader read; then rest, unless it must not (see the module)."""
        self._received(data)
        if self._pace(len(data)) and not self.closing:
            self._rest()

    def _received(self, data: bytes) -> None:
        """Parse a chunk; store its samples, queue its replies."""
        with self._lock:
            frames = self._parser.feed(data)
        raw: list[bytes] = []
        calibrated: list[bytes] = []
        replies: list[Frame] = []
        for frame in frames:  # one pass: a station's pass parses some 125 frames a slot
            if frame.type == FrameType.SAMPLE:
                if not self._starting:
                    raw.append(frame.payload)
            elif frame.type == FrameType.CAL_SAMPLE:
                if not self._starting:
                    calibrated.append(frame.payload)
            else:
                if self._starting and _starts_stream(frame):
                    raw.clear()
                    calibrated.clear()
                    self._fresh_stream()
                replies.append(frame)
        if raw:
            block = decode_samples(raw)
            self._store(block[(block.accel <= self.adc_max).all(axis=1)], self.raw)
        if calibrated:
            self._store(decode_samples(calibrated, calibrated=True), self.calibrated)
        # Replies last: whoever a reply wakes (stop_stream, say) finds every sample read
        # with it stored already.
        for frame in replies:
            self.replies.put(frame)
        self._measure_rate(len(data))

    def _measure_rate(self, size: int) -> None:
        """Count ``size`` bytes read towards the stream's rate over :data:`RATE_WINDOW_S`."""
        now = time.monotonic()
        if self._rate_since is None:
            self._rate_since = now
        self._rate_bytes += size
        if (elapsed := now - self._rate_since) >= RATE_WINDOW_S:
            self._paced = self._rate_bytes / elapsed <= UNPACED_ABOVE_BYTES_PER_S
            self._rate_since, self._rate_bytes = now, 0

    def _pace(self, size: int) -> bool:
        """Whether to rest after a read of ``size`` bytes: a small one, from a stream no
        faster than :data:`UNPACED_ABOVE_BYTES_PER_S`, nobody waiting on the port."""
        return self._paced and size < PACE_BELOW_BYTES and not self._attending

    def _rest(self) -> None:
        """Leave the port to the station's reads until someone waits on it or nobody has
        read it for :data:`REST_S`; a read of the station's in progress ends first."""
        with self._port_lock:
            self._wake.clear()
            if self._attending or self.closing:
                return
            self._resting = True
            self._read_at = time.monotonic()
        while (left := self._read_at + REST_S - time.monotonic()) > 0:
            if self._wake.wait(left):
                break
        with self._port_lock:
            self._resting = False

    def connection_lost(self, exc: BaseException | None) -> None:
        """The reader thread ended: by :meth:`PutterDriver.close`, or the link failed."""
        if self.closing:
            return
        if exc is None or isinstance(exc, (serial.SerialException, OSError)):
            reason = exc if exc is not None else "port closed"
            self.fail(DeviceDisconnectedError(f"putter at {self.name} disconnected: {reason}"))
        else:  # a bug must not leave the station waiting forever, nor pass unseen
            log.error("putter reader stopped", exc_info=exc)
            self.fail(ProtocolError(f"putter at {self.name}: reader stopped: {exc!r}"))

    def _fresh_stream(self) -> None:
        """The unit acknowledged START_STREAM: its samples from here on are the new
        stream's, counted from 0; none held from before is handed out (only the reader's
        thread stores samples, so none of an earlier stream can follow)."""
        with self._lock:
            self._seq.restart()
        self.raw.drain()
        self.calibrated.drain()
        self._starting = False

    def _store(self, block: SampleBlock, buffer: SampleBuffer) -> None:
        if not len(block):
            return
        with self._lock:
            block.seq[:] = self._seq.unwrap(block.seq)
            self._samples += len(block)
        buffer.append(block)


def _starts_stream(frame: Frame) -> bool:
    """Whether ``frame`` is the unit's ACK of a START_STREAM."""
    return frame.type == FrameType.ACK and frame.payload[:1] == bytes((FrameType.START_STREAM,))
