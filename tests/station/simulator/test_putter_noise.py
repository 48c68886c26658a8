"""The virtual putter's samples depend on their number only, not on how they are batched."""

import numpy as np

from station.simulator import VirtualPutter


def test_a_seed_gives_the_same_samples_however_they_are_batched() -> None:
    whole = VirtualPutter(seed=3).trace(0.0, 1000)
    batched = VirtualPutter(seed=3)
    parts = [batched.trace(0.0, 1), batched.trace(0.002, 399), batched.trace(0.8, 600)]
    np.testing.assert_array_equal(whole[:, 1:], np.concatenate(parts)[:, 1:])
    assert not np.array_equal(whole[:, 1:], VirtualPutter(seed=4).trace(0.0, 1000)[:, 1:])
