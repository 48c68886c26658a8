"""The virtual putter: the whole protocol over a pty or a socket, with physics inside.

It runs in a thread of its own. Tests and demos script the operator through
:meth:`VirtualPutter.move_to` and check results against :attr:`VirtualPutter.truth`;
``calstation simulate`` runs one in its own process.
"""

import contextlib
import logging
import math
import select
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Final

import numpy as np
from scipy.spatial.transform import Rotation

from station.closing import Closing
from station.device.messages import DeviceCalibration, Identity
from station.device.protocol import (
    CAL_SAMPLE_DTYPE,
    DEFAULT_RATE_HZ,
    MAX_CALIBRATED_RATE_HZ,
    MAX_RATE_HZ,
    PAYLOAD_LENGTHS,
    RATE_STRUCT,
    SAMPLE_DTYPE,
    ErrorCode,
    Frame,
    FrameParser,
    FrameType,
    StreamMode,
    encode_frame,
    encode_text,
)
from station.poses import Pose, pose
from station.sensor import ADC_MAX, AXES, GYRO_DPS_PER_LSB, TEMP_C_PER_LSB
from station.simulator.clock import VirtualClock
from station.simulator.faults import Faults
from station.simulator.motion import Handling, MotionModel
from station.simulator.sensor import SensorTruth, Thermal, accelerometer_counts, gyro_rates
from station.simulator.transport import Link, PtyLink, SocketLink

log = logging.getLogger(__name__)

FIRMWARE_VERSION: Final = "1.4.2"
SENSOR_PART: Final = "KXM52-1050"
#: Most samples generated in one pass of the loop (a slow machine catches up in steps).
MAX_CHUNK: Final = 2048
_COMMANDS: Final = frozenset(
    {
        FrameType.IDENTIFY,
        FrameType.START_STREAM,
        FrameType.STOP_STREAM,
        FrameType.SET_RATE,
        FrameType.WRITE_CAL,
        FrameType.READ_CAL,
    }
)


def _int16(values: np.ndarray, lsb: float) -> np.ndarray:
    return np.clip(np.rint(values / lsb), -32768, 32767)


class VirtualPutter(Closing):
    """A simulated putter: sensor model, motion model, firmware and a serial port.

    ``seed`` fixes the unit's parameters and its noise; ``serial`` is the serial
    number on its label; ``speed`` runs its clock faster than real time.
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
    ) -> None:
        encode_text(serial, 16)
        # One generator per stream of draws, each drawn in sample order: a sample's noise
        # and faults then depend on its number only, not on how many samples one pass of
        # the loop makes (which follows how busy the machine is).
        (
            truth_rng,
            motion_rng,
            self._accel_rng,
            self._drop_rng,
            self._gyro_rng,
            self._corrupt_rng,
            self._bit_rng,
        ) = np.random.default_rng(seed).spawn(7)
        self._truth = SensorTruth.draw(truth_rng)
        self._label = serial
        self.clock = VirtualClock(speed)
        self.faults = faults or Faults()
        self.thermal = thermal or Thermal()
        self._motion = MotionModel(pose(start_pose).rotation, motion_rng, handling)
        self._calibration = DeviceCalibration.factory_default()
        self._rate_hz = rate_hz
        self._mode: StreamMode | None = None
        self._stream_t0 = 0.0
        self._emitted = 0
        self._seq = 0
        self._stream_samples = 0
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
            self._mode = None
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
        return self._calibration

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
            first: int | None = None
            if self._mode is not None:
                index = max(self._emitted, math.ceil((start - self._stream_t0) * self._rate_hz))
                first = self._seq + index - self._emitted
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

    # -- firmware ---------------------------------------------------------------------

    def _run(self) -> None:
        while not self._stop.is_set():
            link = self._link
            if link is None:
                self._stop.wait(0.005)
                continue
            try:
                readable, _, _ = select.select([link], [], [], 0.002)
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
                    self._answer(link, frame)
        self._stream(link)
        if self._link is link:
            with contextlib.suppress(OSError):
                link.flush()

    def _answer(self, link: Link, frame: Frame) -> None:
        kind = frame.type
        if kind not in _COMMANDS:
            self._error(link, kind, ErrorCode.UNKNOWN_COMMAND, f"unknown command 0x{kind:02x}")
            return
        low, high = PAYLOAD_LENGTHS[kind]
        if not low <= len(frame.payload) <= high:
            self._error(link, kind, ErrorCode.BAD_LENGTH, f"payload of {len(frame.payload)} B")
            return
        if kind == FrameType.IDENTIFY:
            identity = Identity(self.reported_serial, FIRMWARE_VERSION, SENSOR_PART)
            link.send(encode_frame(FrameType.IDENTITY, identity.encode()))
            return
        if kind == FrameType.READ_CAL:
            link.send(encode_frame(FrameType.CALIBRATION, self._calibration.encode_reply()))
            return
        if kind == FrameType.START_STREAM:
            mode = frame.payload[0]
            if mode not in (StreamMode.RAW, StreamMode.CALIBRATED):
                self._error(link, kind, ErrorCode.BAD_VALUE, f"stream mode {mode}")
                return
            if mode == StreamMode.CALIBRATED and self._rate_hz > MAX_CALIBRATED_RATE_HZ:
                self._error(link, kind, ErrorCode.BAD_VALUE, "rate too high for calibrated")
                return
            self._mode = StreamMode(mode)
            self._restart_timing()
            self._seq = 0
            self._stream_samples = 0
        elif kind == FrameType.STOP_STREAM:
            self._mode = None
        elif kind == FrameType.SET_RATE:
            (rate,) = RATE_STRUCT.unpack(frame.payload)
            if not 1 <= rate <= MAX_RATE_HZ:
                self._error(link, kind, ErrorCode.BAD_VALUE, f"rate {rate} not in 1..1000")
                return
            if self._mode == StreamMode.CALIBRATED and rate > MAX_CALIBRATED_RATE_HZ:
                self._error(link, kind, ErrorCode.BAD_VALUE, "rate too high for calibrated")
                return
            self._rate_hz = rate
            self._restart_timing()
        elif kind == FrameType.WRITE_CAL:
            try:
                self._calibration = DeviceCalibration.decode(frame.payload)
            except ValueError:
                self._error(link, kind, ErrorCode.BAD_VALUE, "coefficients not finite")
                return
        link.send(encode_frame(FrameType.ACK, bytes((kind,))))

    def _error(self, link: Link, command: int, code: ErrorCode, text: str) -> None:
        payload = bytes((command, code)) + text.encode("ascii")[:64]
        link.send(encode_frame(FrameType.ERROR, payload))

    def _restart_timing(self) -> None:
        self._stream_t0 = self.clock.now()
        self._emitted = 0

    def _stream(self, link: Link) -> None:
        if self._mode is None:
            return
        rate = self._rate_hz
        due = int((self.clock.now() - self._stream_t0) * rate) + 1 - self._emitted
        count = min(due, MAX_CHUNK)
        if self.faults.disconnect_after is not None:
            count = min(count, self.faults.disconnect_after - self._stream_samples)
            if count <= 0:
                self.unplug()
                return
        if count <= 0:
            return
        t = self._stream_t0 + (self._emitted + np.arange(count)) / rate
        self._emitted += count
        link.send(self._frames(t))

    def _sense(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Accelerometer counts, gyro and temperature fields (protocol counts) at ``t``."""
        self._motion.never_settles = self.faults.never_settle
        kin = self._motion.evaluate(t)
        temperature = self.thermal.at(t)
        acc = accelerometer_counts(self._truth, kin.force_g, temperature, self._accel_rng)
        if self.faults.saturate_axis is not None:
            acc[:, AXES.index(self.faults.saturate_axis)] = ADC_MAX
        gyro = gyro_rates(self._truth, kin.rate_dps, kin.force_g, self._gyro_rng)
        return acc, _int16(gyro, GYRO_DPS_PER_LSB), _int16(temperature, TEMP_C_PER_LSB)

    def trace(self, start_s: float, count: int) -> np.ndarray:
        """``count`` raw samples from simulated time ``start_s``, without the wire.

        Rows are as :meth:`station.device.PutterDriver.drain` returns them (sequence
        number counting from 0, counts, deg/s, °C), quantised as on the wire: for
        testing what consumes samples at full speed.
        """
        t = start_s + np.arange(count) / self._rate_hz
        acc, gyro, temperature = self._sense(t)
        return np.column_stack(
            (np.arange(count), acc, gyro * GYRO_DPS_PER_LSB, temperature * TEMP_C_PER_LSB)
        )

    def _frames(self, t: np.ndarray) -> bytes:
        count = len(t)
        acc, gyro, temperature = self._sense(t)
        calibrated = self._mode == StreamMode.CALIBRATED
        rec = np.empty(count, dtype=CAL_SAMPLE_DTYPE if calibrated else SAMPLE_DTYPE)
        rec["seq"] = (self._seq + np.arange(count)) & 0xFFFF
        rec["acc"] = self._calibration.apply(acc) if calibrated else acc
        rec["gyro"] = gyro
        rec["temp"] = temperature
        self._seq += count
        self._stream_samples += count
        kind = FrameType.CAL_SAMPLE if calibrated else FrameType.SAMPLE
        keep = self._drop_rng.random(count) >= self.faults.drop_rate
        corrupt = self._corrupt_rng.random(count) < self.faults.corrupt_rate
        size = rec.dtype.itemsize
        payload = rec.tobytes()
        out = bytearray()
        for i in np.flatnonzero(keep):
            frame = encode_frame(kind, payload[i * size : (i + 1) * size])
            if corrupt[i]:
                flipped = bytearray(frame)
                bit = int(self._bit_rng.integers(len(frame) * 8))
                flipped[bit // 8] ^= 1 << (bit % 8)
                frame = bytes(flipped)
            out += frame
        return bytes(out)
