"""The geometric residual of a still pose and its Jacobian, in normalised counts.

Every solve works in normalised counts v = (a − 2048)/819.2 (nominal offset and
sensitivity, [Song2006]_ Table 1), where the unknowns are all of order 1: offsets o near
0, sensitivities s near 1, C near the identity. The residual of pose i is

    r_i = |C·(v_i − o)| − 1                               ([Song2006]_ eqs. 7, 8)

and its Jacobian J (N × p) both drives the Levenberg–Marquardt fit and measures the
geometry: cond(J) is the **condition number** reported and bounded for every method
(parameter errors grow with it; it is independent of the method that found o and C).
"""

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.calibration.model import Model
from station.domain.sensors.sensor import NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G

#: Default maximum condition number of a solve's Jacobian (normalised counts).
MAX_CONDITION = 1.0e3

#: Indices of the six free entries of an upper-triangular 3×3 matrix, row by row.
UPPER = np.triu_indices(3)


def unpack(theta: FloatArray, model: Model) -> tuple[FloatArray, FloatArray]:
    """θ as (o, C): θ = (o, s) with C = diag(1/s) for six, θ = (o, C_upper) for nine."""
    if model == "six":
        return theta[:3], np.diag(1.0 / theta[3:6])
    c = np.zeros((3, 3))
    c[UPPER] = theta[3:9]
    return theta[:3], c


def pack(offset: FloatArray, c: FloatArray, model: Model) -> FloatArray:
    """θ of (o, C), as :func:`unpack` reads it."""
    tail = 1.0 / np.diag(c) if model == "six" else c[UPPER]
    return np.concatenate([offset, tail])


def normalise(counts: FloatArray) -> FloatArray:
    """Counts → normalised counts v = (a − 2048)/819.2."""
    return (counts - NOMINAL_OFFSET_COUNTS) / NOMINAL_SENSITIVITY_COUNTS_PER_G


def jacobian_six(offset: FloatArray, sensitivity: FloatArray, v: FloatArray) -> FloatArray:
    """∂r/∂(o, s) of the 6-parameter model, C = diag(1/s); batched.

    Args:
        offset, sensitivity: shape (..., 3), normalised.
        v: shape (..., N, 3), normalised pose means.

    Returns:
        Shape (..., N, 6): columns ∂r/∂o_j = −n_j/s_j, ∂r/∂s_j = −n_j·d_j/s_j², with
        d = v − o and n = g/|g| the unit calibrated gravity.
    """
    s = sensitivity[..., None, :]
    d = v - offset[..., None, :]
    g = d / s
    n = g / np.sqrt(np.einsum("...i,...i->...", g, g))[..., None]
    out = np.empty((*n.shape[:-1], 6))
    np.divide(-n, s, out=out[..., :3])
    np.multiply(out[..., :3], g, out=out[..., 3:])  # −n_j/s_j · d_j/s_j
    return out


def jacobian_nine(offset: FloatArray, c: FloatArray, v: FloatArray) -> FloatArray:
    """∂r/∂(o, C_upper) of the 9-parameter model, shape (N, 9).

    Columns ∂r/∂o = −nᵀC and ∂r/∂C_jk = n_j·d_k for the six upper entries j ≤ k.
    """
    d = v - offset
    g = d @ c.T
    n = g / np.linalg.norm(g, axis=1, keepdims=True)
    return np.hstack([-n @ c, n[:, UPPER[0]] * d[:, UPPER[1]]])


def condition_number(jacobian: FloatArray) -> FloatArray:
    """2-norm condition number of J (..., N, p), shape (...,); ∞ for a rank-deficient J.

    Computed as √(λ_max/λ_min) of JᵀJ (a symmetric eigenproblem, several times faster
    than an SVD over a batch); exact to a few digits up to cond ≈ 1e7, far above any
    limit a calibration would accept.
    """
    eig = np.linalg.eigvalsh(np.swapaxes(jacobian, -1, -2) @ jacobian)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = eig[..., -1] / eig[..., 0]
    return np.asarray(np.sqrt(np.where(eig[..., 0] > 0, ratio, np.inf)), dtype=np.float64)


def leverage(jacobian: FloatArray) -> FloatArray:
    """Each pose's leverage h_i, the diagonal of the hat matrix J(JᵀJ)⁻¹Jᵀ, shape (N,).

    Computed row by row, (J(JᵀJ)⁻¹ ∘ J)·1, in memory linear in N: the N×N hat matrix is
    never formed. h_i is how strongly pose i pulls the fit toward itself (Σh = p); under
    noise σ its residual has standard deviation σ·√(1 − h_i).
    """
    inverse = np.linalg.pinv(jacobian.T @ jacobian)
    return np.asarray(np.einsum("ij,ij->i", jacobian @ inverse, jacobian), dtype=np.float64)
