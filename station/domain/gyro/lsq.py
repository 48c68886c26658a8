"""Linear least squares by SVD with standard errors: the one solver of the gyro fit.

For y = X·θ + e with white e, on the columns of X scaled to unit norm (so the rank
cut ``RCOND`` is unit-free), θ comes from ``numpy.linalg.lstsq`` (SVD, never the
normal equations) and its covariance from the pseudo-inverse::

    Cov(θ) = σ²·X⁺·X⁺ᵀ,   σ² = RSS / (n − rank)

Only estimable parameters (those outside the null space of X) have a meaningful
value and variance; the caller decides which those are.
"""

from dataclasses import dataclass

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.gyro.identifiability import RCOND, normalised


@dataclass(frozen=True)
class LeastSquares:
    """Solution on the chosen columns: θ, its standard errors (NaN when dof = 0), RSS."""

    coef: FloatArray
    stderr: FloatArray
    rss: float
    rank: int
    dof: int


def solve(design: FloatArray, y: FloatArray) -> LeastSquares:
    """Least-squares solution of ``design @ θ ≈ y`` (see module docstring)."""
    n, p = design.shape
    if p == 0:
        return LeastSquares(np.zeros(0), np.zeros(0), float(y @ y), 0, n)
    norms = np.linalg.norm(design, axis=0)
    norms = np.where(norms > 0, norms, 1.0)
    z = normalised(design)
    coef_z, _, rank, _ = np.linalg.lstsq(z, y, rcond=RCOND)
    residual = y - z @ coef_z
    rss = float(residual @ residual)
    dof = n - int(rank)
    pinv = np.linalg.pinv(z, rcond=RCOND)
    if dof > 0:
        variance = rss / dof * np.einsum("ij,ij->i", pinv, pinv)
        stderr = np.sqrt(variance) / norms
    else:
        stderr = np.full(p, np.nan)
    return LeastSquares(coef_z / norms, stderr, rss, int(rank), dof)
