"""The simulated test plan is the paper's: 3 m arm, −30 … +30 g in 3 g steps."""

import numpy as np
import pytest

from station.domain.gyro.simulate import G0, CentrifugePlan, default_mounts, dwells


def test_every_axis_sees_minus_30_to_plus_30_g_in_3_g_steps() -> None:
    _, acc = dwells(CentrifugePlan())
    expected = np.arange(-30.0, 31.0, 3.0)
    for axis in range(3):
        levels = np.unique(np.round(acc[:, axis], 9))
        assert set(expected) <= set(levels)


def test_spin_rate_gives_a_equal_omega_squared_r() -> None:
    plan = CentrifugePlan()
    spin = np.radians(plan.spin_dps(np.array([30.0])))[0]
    assert spin**2 * plan.arm_m / G0 == pytest.approx(30.0)
    assert np.degrees(spin) == pytest.approx(567.3, abs=0.1)  # the paper ran ~575 deg/s


def test_both_spin_directions_and_both_mountings_per_axis() -> None:
    rate, acc = dwells(CentrifugePlan(rate_table=False))
    for i in range(3):
        spun = np.abs(rate[:, i]) > 0
        assert np.any(rate[spun, i] > 0)
        assert np.any(rate[spun, i] < 0)
        assert set(np.sign(acc[spun, i])) == {-1.0, 1.0}  # gravity up and down
    assert len(default_mounts()) == 12


def test_rate_table_steps_have_gravity_up_and_down() -> None:
    rate, acc = dwells(CentrifugePlan(mounts=(), table_rates_dps=(100.0,)))
    assert rate.shape == (3 * 2 * 3, 3)
    for i in range(3):
        rows = np.abs(acc[:, i]) == 1.0
        assert set(acc[rows, i]) == {-1.0, 1.0}
        assert set(rate[rows, i]) == {-100.0, 0.0, 100.0}
