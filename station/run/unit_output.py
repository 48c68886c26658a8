"""The unit's own calibrated output, checked once its coefficients are written.

After the write-back the unit streams calibrated samples; :class:`UnitOutputCheck`
gathers :data:`UNIT_OUTPUT_SAMPLES` of them and answers how far their mean |g| lies from
1 g, in mg. A unit that sends nothing for :data:`STALL_S` counts as gone.
"""

import time

import numpy as np

from station.arrays import FloatArray as Array
from station.device import DeviceTimeoutError, PutterDriver

#: Calibrated samples averaged to check the unit's own output.
UNIT_OUTPUT_SAMPLES = 256
#: Wall-clock seconds without a sample before the unit counts as gone.
STALL_S = 2.0


class UnitOutputCheck:
    """The calibrated samples received so far, and when the last one came."""

    def __init__(self) -> None:
        self._rows: list[Array] = []
        self._last_arrival = time.monotonic()

    def poll(self, driver: PutterDriver) -> float | None:
        """The unit's |g| error in mg once enough samples came (the stream then stops).

        Raises :class:`station.device.errors.DeviceTimeoutError` when the unit went quiet.
        """
        rows = driver.drain_calibrated()
        now = time.monotonic()
        if len(rows):
            self._rows.append(rows)
            self._last_arrival = now
        elif now - self._last_arrival > STALL_S:
            raise DeviceTimeoutError(f"no calibrated samples from {driver.url} for {STALL_S:g} s")
        got = np.concatenate(self._rows) if self._rows else np.empty((0, 4))
        if len(got) < UNIT_OUTPUT_SAMPLES:
            return None
        driver.stop_stream()
        g = got[:UNIT_OUTPUT_SAMPLES, 1:4].mean(axis=0)
        return abs(float(np.linalg.norm(g)) - 1.0) * 1000.0
