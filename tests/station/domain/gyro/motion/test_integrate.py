"""Integration on SO(3): exact for constant rates, in the order the samples came."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from station.domain.gyro.motion import integrate_rates
from station.domain.gyro.motion.integrate import ordered_product

rates = st.lists(st.floats(-20.0, 20.0), min_size=3, max_size=3).map(np.array)


@settings(max_examples=60, deadline=None)
@given(
    rate=rates,
    n=st.integers(2, 3000),
    dt=st.floats(1e-4, 0.05),
    jitter_seed=st.integers(0, 2**32 - 1),
)
def test_constant_rate_integrates_to_the_exponential(
    rate: np.ndarray, n: int, dt: float, jitter_seed: int
) -> None:
    """A constant rate ω over [t0, t_end] turns by exp(ω·(t_end − t0)), whatever the steps."""
    steps = dt * np.random.default_rng(jitter_seed).uniform(0.5, 1.5, n - 1)
    t = np.concatenate([[3.0], 3.0 + np.cumsum(steps)])
    got = integrate_rates(t, np.tile(rate, (n, 1)))
    want = Rotation.from_rotvec(rate * (t[-1] - t[0]))
    assert (got.inv() * want).magnitude() < 1e-9


@settings(max_examples=40, deadline=None)
@given(count=st.integers(0, 70), seed=st.integers(0, 2**32 - 1))
def test_ordered_product_is_the_left_to_right_product(count: int, seed: int) -> None:
    steps = Rotation.random(count, random_state=seed) if count else Rotation.identity(0)
    want = Rotation.identity()
    for k in range(count):
        want = want * steps[k]
    assert (ordered_product(steps).inv() * want).magnitude() < 1e-9


def test_body_rates_compose_on_the_right() -> None:
    """90° about body z, then 90° about the turned body's x: R = Rz · Rx (not Rx · Rz)."""
    quarter = np.pi / 2
    t = np.linspace(0.0, 1.0, 501)
    first = integrate_rates(t, np.tile([0.0, 0.0, quarter], (501, 1)))
    second = integrate_rates(t, np.tile([quarter, 0.0, 0.0], (501, 1)))
    got = first * second
    # The end body's x axis is the start body's y axis; its z is the start's x.
    assert np.allclose(got.apply([1.0, 0.0, 0.0]), [0.0, 1.0, 0.0])
    assert np.allclose(got.apply([0.0, 0.0, 1.0]), [1.0, 0.0, 0.0])
