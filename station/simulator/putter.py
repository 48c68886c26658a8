"""The virtual putter: the whole protocol over a pty or a socket, with physics inside.

It runs in a thread of its own. Tests and demos script the operator through
:meth:`VirtualPutter.move_to` and check results against :attr:`VirtualPutter.truth`;
``calstation simulate`` runs one in its own process.

The firmware loop sends the samples that fell due in bursts, every :data:`BURST_S`, as
a real unit's USB-serial adapter delivers them (an FTDI chip holds its receive buffer
until its latency timer, 16 ms by default, runs out); the samples carry their instants
in their sequence numbers, so a burst changes no sample. A command is answered at once:
the loop wakes as soon as the station writes. Waking every 2 ms instead cost 9–13 % of
a core per putter at real time, against 4–5 % now (``benchmarks/bench_putter_cpu.py``),
in every test and demo that streams.
"""

import contextlib
import logging
import select
import threading
from collections.abc import Callable, Iterator
from dataclasses import replace
from pathlib import Path
from typing import Final

import numpy as np
from scipy.spatial.transform import Rotation

from station.device.messages import DeviceCalibration, Identity
from station.device.protocol import FrameParser, encode_text
from station.domain.closing import Closing
from station.domain.constants import DEFAULT_RATE_HZ
from station.domain.sensors.faults import Faults
from station.domain.sensors.sensor_spec import PUTTER_SENSOR, SensorSpec
from station.domain.signals.poses import Pose, pose
from station.domain.signals.samples import SampleBlock
from station.simulator.clock import VirtualClock
from station.simulator.firmware import Firmware
from station.simulator.motion import Handling, MotionModel
from station.simulator.sensor import SensorTruth, Thermal
from station.simulator.stream import SampleStream
from station.simulator.transport import Link, PtyLink, SocketLink

log = logging.getLogger(__name__)

FIRMWARE_VERSION: Final = "1.4.2"
SENSOR_PART: Final = "KXM52-1050"
#: Real seconds between two bursts of samples (an FTDI adapter's default latency timer).
BURST_S: Final = 0.016


class VirtualPutter(Closing):
    """A simulated putter: sensor model, motion model, firmware and a serial port.

    ``seed`` fixes the unit's parameters and its noise; ``serial`` is the serial
    number on its label; ``speed`` runs its clock faster than real time;
    ``noise_counts`` gives the accelerometer's white noise (counts rms) instead of the
    typical :data:`~station.simulator.sensor.ACCEL_NOISE_COUNTS`; ``sensor``: the
    product's sensor it is built with (default: the putter's, DIXX-A12); ``truth`` gives
    the unit's sensor parameters instead of drawing them from the seed.
    """

    def __init__(
        self,
        *,
        seed: int = 0,
        serial: str = "PT000001",
        rate_hz: int = DEFAULT_RATE_HZ,
        speed: float = 1.0,
        faults: Faults | None = None,
        start_pose: str = "face_up",
        handling: Handling | None = None,
        thermal: Thermal | None = None,
        noise_counts: float | None = None,
        sensor: SensorSpec | None = None,
        truth: SensorTruth | None = None,
    ) -> None:
        encode_text(serial, 16)
        # One generator per stream of draws, each drawn in sample order (see SampleStream).
        truth_rng, motion_rng, *stream_rngs = np.random.default_rng(seed).spawn(7)
        self._truth = truth or SensorTruth.draw(truth_rng, sensor)
        if noise_counts is not None:
            self._truth = replace(self._truth, noise_counts=noise_counts)
        self._label = serial
        self.clock = VirtualClock(speed)
        self.faults = faults or Faults()
        self._motion = MotionModel(pose(start_pose).rotation, motion_rng, handling)
        self._stream = SampleStream(
            self._truth,
            self._motion,
            self.clock,
            self.faults,
            thermal or Thermal(),
            tuple(stream_rngs),
            rate_hz,
        )
        self._firmware = Firmware(
            self._stream,
            lambda: Identity(self.reported_serial, FIRMWARE_VERSION, SENSOR_PART),
            DeviceCalibration.factory_default(sensor or PUTTER_SENSOR),
        )
        self._link: Link | None = None
        self._make_link: Callable[[], Link] | None = None
        self._parser = FrameParser(lengths=None)
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # -- serving ----------------------------------------------------------------------

    def serve_pty(self, alias: str | Path | None = None) -> str:
        """Serve on a new pty; return the path the station opens (``alias`` if given)."""
        return self._serve(lambda: PtyLink(Path(alias) if alias is not None else None))

    def serve_socket(self, host: str = "127.0.0.1", port: int = 0) -> str:
        """Serve on TCP; return the ``socket://host:port`` URL (port 0 picks a free one)."""
        first = SocketLink(host, port)
        bound = first.port
        links = iter([first])
        return self._serve(lambda: next(links, None) or SocketLink(host, bound))

    def _serve(self, make_link: Callable[[], Link]) -> str:
        if self._thread is not None:
            raise RuntimeError("the virtual putter is already serving")
        self._make_link = make_link
        self._link = make_link()
        self._thread = threading.Thread(target=self._run, name="virtual-putter", daemon=True)
        self._thread.start()
        return self._link.url

    @property
    def url(self) -> str | None:
        """The port's URL, or None while unplugged."""
        link = self._link
        return link.url if link is not None else None

    def close(self) -> None:
        """Stop serving and release the port."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        with self._lock:
            if self._link is not None:
                self._link.close()
                self._link = None

    def unplug(self) -> None:
        """Pull the cable: the port goes away, the stream stops."""
        with self._lock:
            if self._link is not None:
                self._link.close()
                self._link = None
            self._stream.mode = None
            self._parser = FrameParser(lengths=None)

    def replug(self) -> str:
        """Plug the cable back in; return the port's URL (a new pty path unless aliased)."""
        with self._lock:
            if self._make_link is None:
                raise RuntimeError("the virtual putter is not serving")
            if self._link is None:
                self._link = self._make_link()
            return self._link.url

    # -- the scripted operator --------------------------------------------------------

    @property
    def truth(self) -> SensorTruth:
        """The unit's true sensor parameters."""
        return self._truth

    @property
    def label_serial(self) -> str:
        """The serial number printed on the unit's label."""
        return self._label

    @property
    def reported_serial(self) -> str:
        """The serial number the firmware reports (differs under ``serial_mismatch``)."""
        if not self.faults.serial_mismatch:
            return self._label
        last = "1" if self._label[-1] == "0" else "0"
        return self._label[:-1] + last

    @property
    def stored_calibration(self) -> DeviceCalibration:
        """What the unit's flash holds."""
        return self._firmware.calibration

    @property
    def stored_gyro_calibration(self) -> DeviceCalibration:
        """The gyro coefficients (bias, K⁻¹) the unit's flash holds."""
        return self._firmware.gyro_calibration

    @property
    def thermal(self) -> Thermal:
        """The unit's temperature over simulated time."""
        return self._stream.thermal

    @property
    def orientation(self) -> Rotation:
        """Where the current (or last) move puts the unit."""
        return self._motion.target

    def move_to(
        self,
        target: str | Pose | Rotation,
        duration_s: float = 1.5,
        *,
        wait: bool = False,
        at_s: float | None = None,
    ) -> int | None:
        """Have the operator move the unit to ``target`` over ``duration_s`` simulated seconds.

        The move starts now, or at simulated time ``at_s`` (for :meth:`trace`). With
        ``wait``, return once the unit has settled (tremor below 1 %). Returns the
        sequence number (counted from 0 at the stream's start, as the driver unwraps
        it) of the first sample the move can show in, or None when not streaming.
        """
        if isinstance(target, str):
            target = pose(target)
        rotation = target.rotation if isinstance(target, Pose) else target
        with self._lock:
            start = self.clock.now() if at_s is None else at_s
            self._motion.move_to(rotation, start, duration_s)
            settled = self._motion.settled_at()
            first = self._stream.first_seq_from(start)
        if wait:
            self.clock.sleep(settled - self.clock.now(), self._stop)
        return first

    @property
    def settled_at_s(self) -> float:
        """Simulated time from which the last move's tremor is below 1 %."""
        return self._motion.settled_at()

    def sleep(self, seconds: float) -> None:
        """Let ``seconds`` of simulated time pass."""
        self.clock.sleep(seconds, self._stop)

    @contextlib.contextmanager
    def held(self) -> Iterator[None]:
        """Send nothing while the block runs: moves queued in it (:meth:`move_to` with
        ``at_s``) all shape the samples after it, however long the caller takes (the
        simulated time runs on, and the samples due go out after the block)."""
        with self._lock:
            yield

    # -- firmware ---------------------------------------------------------------------

    def _run(self) -> None:
        while not self._stop.is_set():
            link = self._link
            if link is None:
                self._stop.wait(0.005)
                continue
            try:
                readable, _, _ = select.select([link], [], [], BURST_S)
            except (OSError, ValueError):  # unplugged while waiting
                continue
            with self._lock:
                if self._link is link:
                    self._tick(link, bool(readable))

    def _tick(self, link: Link, readable: bool) -> None:
        if readable:
            try:
                data = link.receive()
            except OSError as exc:  # the station closed its end of the pty
                log.debug("pty read: %s", exc)
                data = b""
            for frame in self._parser.feed(data):
                if not self.faults.mute:
                    link.send(self._firmware.answer(frame))
        self._stream_due(link)
        if self._link is link:
            with contextlib.suppress(OSError):
                link.flush()

    def _stream_due(self, link: Link) -> None:
        stream = self._stream
        if stream.mode is None:
            return
        budget = self.faults.disconnect_after
        if budget is not None and stream.samples_sent >= budget:
            self.unplug()
            return
        t = stream.due()
        if len(t):
            firmware = self._firmware
            link.send(stream.frames(t, firmware.calibration, firmware.gyro_calibration))

    def trace(self, start_s: float, count: int) -> SampleBlock:
        """``count`` raw samples from simulated time ``start_s``, without the wire.

        A block as :meth:`station.device.PutterDriver.drain` returns it (sequence
        number counting from 0, counts, deg/s, °C), quantised as on the wire: for
        testing what consumes samples at full speed.
        """
        return self._stream.trace(start_s, count)
