"""Applying a calibration: counts to g."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.domain.calibration import Calibration, apply
from station.simulator.recording import random_directions
from tests.station.domain.calibration.strategies import true_units


@settings(max_examples=50)
@given(unit=true_units(cross_axis=0.02), seed=st.integers(0, 2**32 - 1), n=st.integers(1, 50))
def test_the_exact_calibration_inverts_the_sensor(unit, seed: int, n: int) -> None:  # type: ignore[no-untyped-def]
    g = random_directions(np.random.default_rng(seed), n) * 1.7
    exact = Calibration("nine", unit.offset_counts, np.linalg.inv(unit.counts_per_g))
    np.testing.assert_allclose(apply(exact, unit.still_counts(g)), g, atol=1e-9)


def test_apply_takes_one_sample_or_many() -> None:
    cal = Calibration.from_sensitivity([2000, 2050, 2100], [800, 820, 840])
    np.testing.assert_allclose(apply(cal, [2800, 2050, 1260]), [1.0, 0.0, -1.0])
    block = np.tile([2800.0, 2050, 1260], (4, 1))
    assert apply(cal, block).shape == (4, 3)


def test_to_dict_is_the_public_shape() -> None:
    cal = Calibration.from_sensitivity([2000, 2050, 2100], [800, 820, 840])
    d = cal.to_dict()
    assert d["offset"] == {"x": 2000.0, "y": 2050.0, "z": 2100.0}
    assert d["sensitivity"] == pytest.approx({"x": 800.0, "y": 820.0, "z": 840.0}, rel=1e-14)
    assert d["matrix"] == [[1 / 800, 0, 0], [0, 1 / 820, 0], [0, 0, 1 / 840]]
