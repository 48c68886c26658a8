"""The drift statistic on simulated lines with known truth: no drift, and a drift put in."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.domain.quality.drift import DRIFT_ALPHA, DRIFT_WINDOW, find_drift
from tests.conftest import examples

SPREAD = 207.0  # the datasheet's offset spread, counts


def line(
    rng: np.random.Generator, units: int, drift: float = 0.0, axis: int = 0, quantity: int = 0
) -> tuple[np.ndarray, np.ndarray]:
    """Offsets and sensitivities of ``units`` units, one coefficient drifting per unit."""
    offsets = 2048 + rng.uniform(-SPREAD, SPREAD, (units, 3))
    sensitivities = 819.2 * (1 + rng.uniform(-0.05, 0.05, (units, 3)))
    table = offsets if quantity == 0 else sensitivities
    table[:, axis] += drift * np.arange(units)
    return offsets, sensitivities


@pytest.mark.timeout(60)
def test_a_line_without_drift_warns_at_most_at_the_stated_rate() -> None:
    """300 independent windows: expected false alarms ≤ 0.3 (α = 0.001 per check);
    more than 3 has probability under 0.03 % if the stated rate holds, while a test
    at α = 0.05 per axis would give about 80."""
    rng = np.random.default_rng(15)
    alarms = sum(find_drift(*line(rng, DRIFT_WINDOW)) is not None for _ in range(300))
    assert DRIFT_ALPHA == 0.001
    assert alarms <= 3


@pytest.mark.parametrize(
    ("quantity", "axis", "drift"),
    [(0, 0, 40.0), (0, 2, -40.0), (1, 1, 8.0)],
    ids=["offset-x-rising", "offset-z-falling", "sensitivity-y-rising"],
)
def test_a_drift_put_in_is_found_on_its_axis_with_its_slope(
    quantity: int, axis: int, drift: float
) -> None:
    """40 counts per unit (800 over 20 units, 3.9 σ of the units' spread) is found
    nearly always (the power at 30 counts per unit is 84 %); so is 8 counts/g per unit
    against the sensitivities' ±41 counts/g."""
    rng = np.random.default_rng(axis)
    found = [find_drift(*line(rng, 30, drift, axis, quantity)) for _ in range(20)]
    hits = [f for f in found if f is not None]
    assert len(hits) >= 18
    name = ("offset", "sensitivity")[quantity]
    for hit in hits:
        assert (hit.quantity, hit.axis) == (name, "xyz"[axis])
        assert np.sign(hit.slope_per_unit) == np.sign(drift)
    slopes = [h.slope_per_unit for h in hits]
    # Theil–Sen over 20 units with the units' spread: within a third of the truth.
    assert abs(np.median(slopes) - drift) < abs(drift) / 3
    sentence = hits[0].sentence
    assert sentence.startswith(f"DRIFT: {name} {'xyz'[axis]} ")
    assert ("rising" if drift > 0 else "falling") in sentence


def test_fewer_units_than_the_window_give_no_verdict() -> None:
    offsets, sensitivities = line(np.random.default_rng(0), DRIFT_WINDOW - 1, drift=500.0)
    assert find_drift(offsets, sensitivities) is None


@given(st.permutations(list(range(DRIFT_WINDOW))))
@settings(max_examples=examples(15), deadline=None)
def test_only_the_order_matters_not_the_units_spread(order: list[int]) -> None:
    """A monotone transform of the values changes neither the test nor its verdict."""
    rng = np.random.default_rng(1)
    offsets, sensitivities = line(rng, DRIFT_WINDOW, drift=60.0)
    offsets, sensitivities = offsets[order], sensitivities[order]
    plain = find_drift(offsets, sensitivities)
    squeezed = find_drift(2048 + (offsets - 2048) ** 3 / 1e4, sensitivities)
    assert (plain is None) == (squeezed is None)
    if plain is not None and squeezed is not None:
        assert (plain.quantity, plain.axis) == (squeezed.quantity, squeezed.axis)
        assert plain.p_value == pytest.approx(squeezed.p_value)
