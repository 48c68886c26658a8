"""The classic ±1 g method (eqs. 2, 3)."""

import numpy as np
import pytest

from station.domain.calibration import CalibrationError, NonPositiveScaleError, solve_classic
from station.simulator.recording import six_directions
from station.simulator.sensor import SensorTruth


def jig_poses(unit, tilt_deg: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:  # type: ignore[no-untyped-def]
    counts = unit.still_counts(six_directions(np.random.default_rng(seed), tilt_deg))
    return counts[0::2], counts[1::2]  # rows +x,+y,+z and −x,−y,−z


def test_exact_on_a_perfect_jig() -> None:
    unit = SensorTruth.draw_accelerometer(np.random.default_rng(1))
    cal = solve_classic(*jig_poses(unit, 0.0))
    np.testing.assert_allclose(cal.offset, unit.offset_counts, atol=1e-9)
    np.testing.assert_allclose(cal.sensitivity, unit.sensitivity_counts_per_g, rtol=1e-12)


@pytest.mark.parametrize("tilt", [2.0, 5.0, 10.0])
def test_a_tilted_jig_biases_the_sensitivity_by_one_minus_cos(tilt: float) -> None:
    unit = SensorTruth.draw_accelerometer(np.random.default_rng(2))
    cal = solve_classic(*jig_poses(unit, tilt))
    ratio = cal.sensitivity / unit.sensitivity_counts_per_g
    np.testing.assert_allclose(ratio, np.cos(np.radians(tilt)), rtol=1e-9)


def test_refuses_swapped_poses() -> None:
    unit = SensorTruth.draw_accelerometer(np.random.default_rng(3))
    plus, minus = jig_poses(unit, 0.0)
    with pytest.raises(NonPositiveScaleError, match="swapped"):
        solve_classic(minus, plus)


def test_refuses_bad_shapes_and_values() -> None:
    with pytest.raises(CalibrationError, match="two 3×3 arrays"):
        solve_classic(np.zeros((2, 3)), np.zeros((3, 3)))
    with pytest.raises(CalibrationError, match="not a finite number"):
        solve_classic(np.full((3, 3), np.nan), np.zeros((3, 3)))
