"""Global false-accept and false-reject risks of a decision rule ([JCGM106]_ 9.5).

Model: the process makes units whose true value Y is normal, N(μ, σ_p²); the station
measures y = Y + E with E normal, N(0, u²), u the standard uncertainty of measurement
(U/k). The observed spread of the measured values is σ_obs² = σ_p² + u², so
σ_p = √(σ_obs² − u²) (zero when the measurement explains all the spread). A unit is
accepted when y lies in the acceptance interval [L + w, H − w] (w = 0: simple acceptance;
w = U: guarded acceptance, ILAC-G8:09/2019):

    false accept  R_C = P(Y outside [L, H] and y accepted)
    false reject  R_P = P(Y inside [L, H] and y refused)

computed by quadrature over Y (both are integrals of a normal density times a normal
probability). A missing limit is an unbounded side.

The risks hold for a normal population only (a uniform one of the same spread has no
tails beyond its ends: the normal model then reports false accepts where there are
none). :func:`normality` checks the measured values against it: the Anderson–Darling
test ([Stephens1974]_, :func:`scipy.stats.anderson`, mean and spread estimated) at the
5 % level, shown beside the risks.

.. [JCGM106] JCGM 106:2012, Evaluation of measurement data — The role of measurement
   uncertainty in conformity assessment.
.. [Stephens1974] M. A. Stephens, "EDF Statistics for Goodness of Fit and Some
   Comparisons", Journal of the American Statistical Association 69, 1974.
"""

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np

#: Quadrature points over ±8 σ_p of the process.
_POINTS: Final = 4001
#: Fewest values the normality check judges (Anderson–Darling's critical values hold
#: from 8 on).
MIN_NORMALITY_VALUES: Final = 8
#: The significance level of the normality check.
NORMALITY_LEVEL: Final = 0.05


@dataclass(frozen=True)
class Normality:
    """The Anderson–Darling check of a population against a normal one: its statistic
    A², its p-value (interpolated in Stephens' table, so within 0.01…0.15) and how many
    values."""

    statistic: float
    p_value: float
    values: int

    @property
    def normal(self) -> bool:
        """Not rejected as normal at :data:`NORMALITY_LEVEL`."""
        return self.p_value >= NORMALITY_LEVEL


def normality(values: Sequence[float]) -> Normality | None:
    """The Anderson–Darling normality check of ``values`` (module docstring); None with
    fewer than :data:`MIN_NORMALITY_VALUES` or no spread."""
    from scipy.stats import anderson

    data = np.asarray(values, dtype=np.float64)
    if len(data) < MIN_NORMALITY_VALUES or float(np.ptp(data)) == 0.0:
        return None
    # scipy-stubs spell the method "interpolated"; scipy itself takes "interpolate".
    result = anderson(data, dist="norm", method="interpolate")  # type: ignore[call-overload]
    return Normality(float(result.statistic), float(result.pvalue), len(data))


@dataclass(frozen=True)
class Risks:
    """Fractions of all units: accepted though out of limits, refused though within."""

    false_accept: float
    false_reject: float


def decision_risks(
    mean: float,
    observed_std: float,
    u: float,
    lower: float | None,
    upper: float | None,
    guard: float = 0.0,
) -> Risks:
    """The global risks of accepting on ``[lower + guard, upper − guard]`` (module docstring).

    Args:
        mean, observed_std: the measured values' mean and standard deviation.
        u: the standard uncertainty of one measurement (U/k), same unit.
        lower, upper: the limits (None: unbounded).
        guard: the guard band w (0: simple acceptance).
    """
    from scipy.stats import norm

    low = -np.inf if lower is None else float(lower)
    high = np.inf if upper is None else float(upper)
    sigma_p = float(np.sqrt(max(observed_std**2 - u**2, 0.0)))
    accept_low, accept_high = low + guard, high - guard

    def accepted(y_true: np.ndarray) -> np.ndarray:
        if u <= 0:
            return ((y_true >= accept_low) & (y_true <= accept_high)).astype(np.float64)
        if accept_low > accept_high:
            return np.zeros_like(y_true)
        return np.asarray(
            norm.cdf((accept_high - y_true) / u) - norm.cdf((accept_low - y_true) / u),
            dtype=np.float64,
        )

    if sigma_p == 0.0:  # every unit at the mean
        y = np.array([mean], dtype=np.float64)
        weight = np.array([1.0])
    else:
        y = np.linspace(mean - 8 * sigma_p, mean + 8 * sigma_p, _POINTS)
        weight = norm.pdf(y, mean, sigma_p) * (y[1] - y[0])
    inside = (y >= low) & (y <= high)
    p_accept = accepted(y)
    false_accept = float(np.sum(weight * p_accept * ~inside))
    false_reject = float(np.sum(weight * (1.0 - p_accept) * inside))
    return Risks(
        false_accept=min(max(false_accept, 0.0), 1.0), false_reject=min(max(false_reject, 0.0), 1.0)
    )
