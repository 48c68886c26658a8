"""The unit's own calibrated output, checked once its coefficients are written.

After the write-back the unit streams calibrated samples; :class:`UnitOutputCheck`
gathers :data:`UNIT_OUTPUT_SAMPLES` of them and answers how far their mean |g| lies from
1 g, in mg. A unit that sends nothing for :data:`STALL_S` counts as gone. A whole-unit
run keeps the stream going: the window and the samples after it start the verification
move (:mod:`station.run.gyro_check`).
"""

import time

import numpy as np

from station.device import DeviceTimeoutError, PutterDriver
from station.domain.signals.samples import SampleBlock

#: Calibrated samples averaged to check the unit's own output.
UNIT_OUTPUT_SAMPLES = 256
#: Wall-clock seconds without a sample before the unit counts as gone.
STALL_S = 2.0


class CalibratedSamples:
    """The unit's calibrated samples received so far, and when the last one came."""

    def __init__(self, first: SampleBlock | None = None) -> None:
        self._blocks = [first] if first is not None else []
        self._last_arrival = time.monotonic()

    def drain(self, driver: PutterDriver) -> SampleBlock:
        """Every calibrated sample so far, with those the driver holds now.

        Raises :class:`station.device.DeviceTimeoutError` when the unit sent nothing
        for :data:`STALL_S`.
        """
        block = driver.drain_calibrated()
        now = time.monotonic()
        if len(block):
            self._blocks.append(block)
            self._last_arrival = now
        elif now - self._last_arrival > STALL_S:
            raise DeviceTimeoutError(f"no calibrated samples from {driver.url} for {STALL_S:g} s")
        samples = SampleBlock.concat(self._blocks)
        self._blocks = [samples]
        return samples


class UnitOutputCheck:
    """Gathers the unit's calibrated output and answers its |g| error."""

    def __init__(self, *, keep_streaming: bool = False) -> None:
        self._samples = CalibratedSamples()
        self._keep_streaming = keep_streaming
        #: The samples averaged, and those received after them (once answered).
        self.window = SampleBlock.empty()
        self.rest = SampleBlock.empty()

    def poll(self, driver: PutterDriver) -> float | None:
        """The unit's |g| error in mg once enough samples came (the stream then stops,
        unless it is kept for the verification move).

        Raises :class:`station.device.DeviceTimeoutError` when the unit went quiet.
        """
        got = self._samples.drain(driver)
        if len(got) < UNIT_OUTPUT_SAMPLES:
            return None
        if not self._keep_streaming:
            driver.stop_stream()
        self.window, self.rest = got[:UNIT_OUTPUT_SAMPLES], got[UNIT_OUTPUT_SAMPLES:]
        g = self.window.summary().accel_mean
        return abs(float(np.linalg.norm(g)) - 1.0) * 1000.0
