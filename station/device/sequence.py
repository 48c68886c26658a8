"""Unwrapping the putter's 16-bit sample sequence numbers into a running count."""

import numpy as np

from station.domain.arrays import FloatArray

SEQ_MODULUS = 1 << 16


class SequenceTracker:
    """Unwraps the 16-bit sequence numbers and counts the samples that went missing."""

    def __init__(self) -> None:
        self.last: int | None = None
        self.lost = 0
        self.gaps = 0

    def restart(self) -> None:
        """The unit restarts counting at 0: a first sample numbered 3 means 3 lost."""
        self.last = -1

    def unwrap(self, seq16: FloatArray) -> FloatArray:
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
