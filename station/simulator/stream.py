"""The virtual putter's sample stream: what it senses when, framed as on the wire.

The stream runs on the putter's :class:`~station.simulator.clock.VirtualClock`: at
each tick it emits every sample due since the last one (at most :data:`MAX_CHUNK`),
sensed from the motion, thermal and sensor models and damaged by the
:class:`~station.domain.sensors.faults.Faults` in force.
"""

import math
from typing import Final

import numpy as np

from station.device.messages import DeviceCalibration
from station.device.protocol import (
    CAL_SAMPLE_DTYPE,
    SAMPLE_DTYPE,
    FrameType,
    StreamMode,
    encode_frame,
)
from station.domain.arrays import FloatArray
from station.domain.constants import DEFAULT_RATE_HZ
from station.domain.sensors.faults import Faults
from station.domain.sensors.sensor import AXES, GYRO_DPS_PER_LSB, TEMP_C_PER_LSB
from station.domain.signals.samples import SampleBlock
from station.simulator.clock import VirtualClock
from station.simulator.motion import MotionModel
from station.simulator.sensor import SensorTruth, Thermal, accelerometer_counts, gyro_rates

#: Most samples generated in one pass of the loop (a slow machine catches up in steps).
MAX_CHUNK: Final = 2048


def _int16(values: FloatArray, lsb: float) -> FloatArray:
    return np.clip(np.rint(values / lsb), -32768, 32767)


class SampleStream:
    """Samples of one unit: its physics, its rate, and where the stream stands.

    ``rngs`` are five generators, each drawn in sample order (accelerometer noise,
    drops, gyro noise, corruption, flipped bits), so that a sample's noise and faults
    depend on its number only, not on how many samples one pass of the loop makes.
    """

    def __init__(
        self,
        truth: SensorTruth,
        motion: MotionModel,
        clock: VirtualClock,
        faults: Faults,
        thermal: Thermal,
        rngs: tuple[np.random.Generator, ...],
        rate_hz: int = DEFAULT_RATE_HZ,
    ) -> None:
        self.truth = truth
        self.motion = motion
        self.clock = clock
        self.faults = faults
        self.thermal = thermal
        self._accel_rng, self._drop_rng, self._gyro_rng, self._corrupt_rng, self._bit_rng = rngs
        self.rate_hz = rate_hz
        self.mode: StreamMode | None = None
        self._t0 = 0.0
        self._emitted = 0
        self._seq = 0
        self.samples_sent = 0

    def start(self, mode: StreamMode) -> None:
        """Stream in ``mode`` from now; sequence numbers restart at 0."""
        self.mode = mode
        self.restart_timing()
        self._seq = 0
        self.samples_sent = 0

    def restart_timing(self) -> None:
        """Count due samples from now (after a start or a new rate)."""
        self._t0 = self.clock.now()
        self._emitted = 0

    def first_seq_from(self, start_s: float) -> int | None:
        """Sequence number of the first sample at or after ``start_s``; None unless streaming."""
        if self.mode is None:
            return None
        index = max(self._emitted, math.ceil((start_s - self._t0) * self.rate_hz))
        return self._seq + index - self._emitted

    def due(self) -> FloatArray:
        """Times of the samples due now (at most :data:`MAX_CHUNK`); marks them emitted."""
        rate = self.rate_hz
        count = min(int((self.clock.now() - self._t0) * rate) + 1 - self._emitted, MAX_CHUNK)
        if self.faults.disconnect_after is not None:
            count = min(count, self.faults.disconnect_after - self.samples_sent)
        if count <= 0:
            return np.empty(0)
        t = self._t0 + (self._emitted + np.arange(count)) / rate
        self._emitted += count
        return t

    def sense(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Accelerometer counts, gyro and temperature fields (protocol counts) at ``t``."""
        self.motion.never_settles = self.faults.never_settle
        kin = self.motion.evaluate(t)
        temperature = self.thermal.at(t)
        acc = accelerometer_counts(self.truth, kin.force_g, temperature, self._accel_rng)
        if self.faults.saturate_axis is not None:
            acc[:, AXES.index(self.faults.saturate_axis)] = self.truth.adc_max
        gyro = gyro_rates(self.truth, kin.rate_dps, kin.force_g, self._gyro_rng)
        return acc, _int16(gyro, GYRO_DPS_PER_LSB), _int16(temperature, TEMP_C_PER_LSB)

    def trace(self, start_s: float, count: int) -> SampleBlock:
        """``count`` raw samples from simulated time ``start_s``, without the wire."""
        t = start_s + np.arange(count) / self.rate_hz
        acc, gyro, temperature = self.sense(t)
        return SampleBlock.from_columns(
            np.arange(count, dtype=np.float64),
            acc,
            gyro * GYRO_DPS_PER_LSB,
            temperature * TEMP_C_PER_LSB,
        )

    def frames(
        self, t: FloatArray, calibration: DeviceCalibration, gyro: DeviceCalibration
    ) -> bytes:
        """The SAMPLE (or CAL_SAMPLE) frames of the samples at ``t``, faults applied.

        The calibrated stream applies ``calibration`` to the accelerometer and ``gyro``
        (bias, K⁻¹) to the gyros' readings, then rounds the rates to the wire's 0.02 deg/s.
        """
        count = len(t)
        acc, gyro_counts, temperature = self.sense(t)
        calibrated = self.mode == StreamMode.CALIBRATED
        rec = np.empty(count, dtype=CAL_SAMPLE_DTYPE if calibrated else SAMPLE_DTYPE)
        rec["seq"] = (self._seq + np.arange(count)) & 0xFFFF
        rec["acc"] = calibration.apply(acc) if calibrated else acc
        rec["gyro"] = (
            _int16(gyro.apply(gyro_counts * GYRO_DPS_PER_LSB), GYRO_DPS_PER_LSB)
            if calibrated
            else gyro_counts
        )
        rec["temp"] = temperature
        self._seq += count
        self.samples_sent += count
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
