"""Drift of a station: a common trend in the calibrations of its latest units.

Each unit's offsets and sensitivities are its own, spread over the datasheet's range;
what the station itself does to them (a reference voltage, the fixture's temperature, a
worn jig) is common to every unit it calibrates, and shows as a trend over the units in
the order they were calibrated. For each axis of offset and of sensitivity, over the
last ``window`` passed units, the station computes the Mann–Kendall trend test
(Kendall's τ of the values against their order, :func:`scipy.stats.kendalltau`,
exact p-value for ``window`` ≤ 50 without ties) and the Theil–Sen slope
(:func:`scipy.stats.theilslopes`, counts per unit), both robust to a single odd unit.

Under no drift the units come in random order with respect to their own parameters,
so each p-value is uniform whatever the units' spread: the test's false-alarm rate is
exactly its level. The warning is raised when the smallest of the six p-values is below
``alpha / 6`` (Bonferroni over three axes of two parameters), so a station without drift
warns at a check with probability at most ``alpha`` (default 0.001). A trend is found
once it moves the values by several times their own spread over the window: with
``window`` 20 and offsets spread uniformly over the datasheet's ±207 counts (σ 120), a
drift of 30 counts per unit (600 counts over the window) is found in 84 % of windows,
25 in half, 15 in 7 % (a lot of units spread less than the datasheet finds less;
``tests/station/domain/quality/test_drift.py``).
"""

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.sensors.sensor import AXES

#: Passed units the statistic looks at.
DRIFT_WINDOW = 20
#: Probability that a station without drift warns at one check (all six tests together).
DRIFT_ALPHA = 0.001

_QUANTITIES = (("offset", "counts"), ("sensitivity", "counts/g"))


@dataclass(frozen=True)
class Drift:
    """The strongest trend found: which quantity and axis, its slope and p-value."""

    quantity: str
    axis: str
    slope_per_unit: float
    unit: str
    p_value: float
    units: int

    @property
    def sentence(self) -> str:
        """One line for the operator's screen, key words first."""
        way = "rising" if self.slope_per_unit > 0 else "falling"
        return (
            f"DRIFT: {self.quantity} {self.axis} {way} over the last {self.units} units "
            f"({self.slope_per_unit:+.2f} {self.unit}/unit, p {self.p_value:.1g}): "
            "check the station"
        )


def find_drift(
    offsets: Sequence[Sequence[float]] | FloatArray,
    sensitivities: Sequence[Sequence[float]] | FloatArray,
    window: int = DRIFT_WINDOW,
    alpha: float = DRIFT_ALPHA,
) -> Drift | None:
    """The trend in the last ``window`` units' coefficients (oldest first), if significant.

    ``offsets`` and ``sensitivities`` are N-by-3, in the order the units were calibrated.
    Fewer than ``window`` units: no verdict (None).
    """
    values = (np.asarray(offsets, dtype=np.float64), np.asarray(sensitivities, dtype=np.float64))
    if len(values[0]) < window:
        return None
    # Imported here: scipy.stats takes about as long to import as the rest of the
    # station's loop, and a station that starts with fewer units than a window needs none.
    from scipy import stats

    order = np.arange(window, dtype=np.float64)
    tests = 2 * len(AXES)
    best: Drift | None = None
    for (quantity, unit), table in zip(_QUANTITIES, values, strict=True):
        for axis, column in zip(AXES, table[-window:].T, strict=True):
            if np.ptp(column) == 0:
                continue
            p_value = float(stats.kendalltau(order, column).pvalue)
            if p_value >= alpha / tests or (best is not None and p_value >= best.p_value):
                continue
            slope = float(stats.theilslopes(column, order).slope)
            best = Drift(quantity, axis, slope, unit, p_value, window)
    return best
