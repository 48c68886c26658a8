"""A clock for the virtual putter that may run faster than real time."""

import threading
import time


class VirtualClock:
    """Simulated seconds since creation, advancing ``speed`` times faster than real time.

    Everything the virtual putter does (sample instants, motions, settling) is in
    this time, so a test at ``speed=20`` goes through a whole unit in seconds while
    the samples on the wire still carry device time in their sequence numbers.
    """

    def __init__(self, speed: float = 1.0) -> None:
        if not speed > 0:
            raise ValueError(f"clock speed must be positive, got {speed}")
        self.speed = speed
        self._origin = time.monotonic()

    def now(self) -> float:
        """Simulated seconds elapsed."""
        return (time.monotonic() - self._origin) * self.speed

    def sleep(self, seconds: float, stop: threading.Event | None = None) -> None:
        """Sleep ``seconds`` of simulated time (wakes early if ``stop`` is set)."""
        real = max(0.0, seconds) / self.speed
        if stop is None:
            time.sleep(real)
        else:
            stop.wait(real)
