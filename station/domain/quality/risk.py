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

.. [JCGM106] JCGM 106:2012, Evaluation of measurement data — The role of measurement
   uncertainty in conformity assessment.
"""

from dataclasses import dataclass
from typing import Final

import numpy as np

#: Quadrature points over ±8 σ_p of the process.
_POINTS: Final = 4001


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
        false_accept=min(max(false_accept, 0.0), 1.0),
        false_reject=min(max(false_reject, 0.0), 1.0),
    )
