"""The station's side of the wire, as a :class:`serial.threaded.Protocol`.

pyserial's :class:`~serial.threaded.ReaderThread` reads the port and hands every
chunk to :meth:`PutterLink.data_received`; the link cuts it into frames with the
:class:`~station.device.protocol.FrameParser` (the putter's frames carry a length
and a CRC, not the terminator pyserial's ``Packetizer`` splits on), unwraps the
samples' sequence numbers into the two sample buffers and queues every other frame
as a reply for the command waiting on it. When the thread ends,
:meth:`connection_lost` records why, so that nobody waits for a dead link.
"""

import logging
import queue
import threading
import time

import serial
from serial.threaded import Protocol

from station.device.buffer import SampleBuffer
from station.device.errors import DeviceDisconnectedError, DeviceError, ProtocolError
from station.device.protocol import Frame, FrameParser, FrameType, decode_samples
from station.device.sequence import SequenceTracker
from station.device.stats import LinkCounters
from station.domain.samples import SampleBlock
from station.domain.sensor import ADC_MAX

log = logging.getLogger(__name__)

#: A chunk smaller than this (bytes: ~100 sample frames) has the reader rest for
#: :data:`PACE_S` before it reads again, so that the next read takes a batch. At the
#: putter's 512 frames a second the port would otherwise wake the reader once per
#: 20-byte frame, each wake costing some 30 times the frame's parsing (issue 28). A
#: tenth of a second is the screen's redraw period: the station looks at the samples
#: no more often than that, so one batch a redraw delays nothing it shows. A command
#: waiting for its reply wakes the reader at once (:meth:`PutterLink.expect_reply`).
PACE_BELOW_BYTES = 2048
PACE_S = 0.1
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
        self._samples = 0
        self._lock = threading.Lock()
        self._failure: DeviceError | None = None
        #: Set while a command waits for its reply: the reader does not rest then.
        self._reply_due = threading.Event()
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

    def expect_reply(self, due: bool) -> None:
        """A command was sent and waits for its reply (``due``), or has it."""
        if due:
            self._reply_due.set()
        else:
            self._reply_due.clear()

    def restart_sequence(self) -> None:
        """The unit is about to count its samples from 0 again."""
        with self._lock:
            self._seq.restart()

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
        """Parse a chunk; store its samples, queue its replies."""
        with self._lock:
            frames = self._parser.feed(data)
        raw = [f.payload for f in frames if f.type == FrameType.SAMPLE]
        calibrated = [f.payload for f in frames if f.type == FrameType.CAL_SAMPLE]
        if raw:
            block = decode_samples(raw)
            self._store(block[(block.accel <= self.adc_max).all(axis=1)], self.raw)
        if calibrated:
            self._store(decode_samples(calibrated, calibrated=True), self.calibrated)
        for frame in frames:
            if frame.type not in (FrameType.SAMPLE, FrameType.CAL_SAMPLE):
                self.replies.put(frame)
        if self._pace(len(data)) and not self.closing:
            self._reply_due.wait(PACE_S)

    def _pace(self, size: int) -> bool:
        """Whether to rest after a chunk of ``size`` bytes: a small one, from a stream
        no faster than :data:`UNPACED_ABOVE_BYTES_PER_S` over the last window."""
        now = time.monotonic()
        if self._rate_since is None:
            self._rate_since = now
        self._rate_bytes += size
        if (elapsed := now - self._rate_since) >= RATE_WINDOW_S:
            self._paced = self._rate_bytes / elapsed <= UNPACED_ABOVE_BYTES_PER_S
            self._rate_since, self._rate_bytes = now, 0
        return self._paced and size < PACE_BELOW_BYTES

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

    def _store(self, block: SampleBlock, buffer: SampleBuffer) -> None:
        if not len(block):
            return
        with self._lock:
            block.seq[:] = self._seq.unwrap(block.seq)
            self._samples += len(block)
        buffer.append(block)
