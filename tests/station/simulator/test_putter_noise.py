"""The virtual putter's samples depend on their number only, not on how they are batched."""

import numpy as np

from station.domain.signals.samples import SampleBlock
from station.simulator import VirtualPutter


def readings(block: SampleBlock) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Everything a block holds but its sequence numbers."""
    return block.accel, block.gyro, block.temperature


def test_a_seed_gives_the_same_samples_however_they_are_batched() -> None:
    whole = VirtualPutter(seed=3).trace(0.0, 1000)
    batched = VirtualPutter(seed=3)
    parts = [batched.trace(0.0, 1), batched.trace(0.002, 399), batched.trace(0.8, 600)]
    for one, other in zip(readings(whole), readings(SampleBlock.concat(parts)), strict=True):
        np.testing.assert_array_equal(one, other)
    other_seed = VirtualPutter(seed=4).trace(0.0, 1000)
    assert not np.array_equal(whole.accel, other_seed.accel)
