"""Least-squares calibration from N ≥ 6 (6-parameter) or N ≥ 9 (9-parameter) poses.

Model: every still pose i sees exactly 1 g, so with g_i = C·(a_i − o),

    r_i(θ) = |C·(a_i − o)| − 1 = 0,

[Song2006]_ eqs. 7, 8 written as a geometric residual in g. The 6-parameter model has
C = diag(1/s) (θ = o, s; [Song2006]_ eq. 5); the 9-parameter model has C upper-triangular
(θ = o and C's six entries), which adds the three non-orthogonality terms that carry
cross-axis sensitivity and mounting misalignment (outside [Song2006]_'s model). An upper-triangular
C is unique: |g| cannot see a rotation, so a full 3×3 C is not identifiable.

Fit in two steps, in normalised counts (:mod:`station.domain.calibration.residual`):

1. **Algebraic start.** The constraint (v − o)ᵀ M (v − o) = 1 with M = CᵀC is linear
   in the coefficients of a quadric, vᵀMv + bᵀv + c = 0. The null vector (smallest
   right singular vector) of the N×7 (diagonal M) or N×10 (full M) design matrix gives
   them; o = −M⁻¹b/2 and C is the Cholesky factor of M/(oᵀMo − c). With six poses and
   the diagonal model this is exactly the paper's eq. 10 solution.
2. **Levenberg–Marquardt** (MINPACK through :func:`scipy.optimize.least_squares`) on
   r(θ), the maximum-likelihood fit when the pose means carry isotropic noise.

Standard errors, when N exceeds the number of unknowns p, come from
cov(θ) = σ̂²·(JᵀJ)⁻¹ with σ̂² = Σr²/(N − p).
"""

from dataclasses import dataclass

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.calibration.errors import (
    CalibrationError,
    IllConditionedError,
    NonPositiveScaleError,
)
from station.domain.calibration.geometry import GeometryLimits, check_poses, refuse_beyond_datasheet
from station.domain.calibration.model import Calibration, Model
from station.domain.calibration.residual import (
    MAX_CONDITION,
    condition_number,
    jacobian_nine,
    jacobian_six,
    leverage,
    normalise,
    pack,
    unpack,
)
from station.domain.calibration.solution import CoefficientErrors, Solution, quality_of
from station.domain.sensors.sensor import NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G

UNKNOWNS: dict[Model, int] = {"six": 6, "nine": 9}


@dataclass(frozen=True)
class _Parametrisation:
    """θ ↔ (o, C) in normalised counts: six model θ = (o, s), nine model θ = (o, C_upper)."""

    model: Model

    def residual(self, theta: FloatArray, v: FloatArray) -> FloatArray:
        offset, c = unpack(theta, self.model)
        return np.asarray(np.linalg.norm((v - offset) @ c.T, axis=1) - 1.0, dtype=np.float64)

    def jacobian(self, theta: FloatArray, v: FloatArray) -> FloatArray:
        if self.model == "six":
            return jacobian_six(theta[:3], theta[3:6], v)
        offset, c = unpack(theta, self.model)
        return jacobian_nine(offset, c, v)


def algebraic_start(v: FloatArray, model: Model) -> tuple[FloatArray, FloatArray]:
    """Offset and C (normalised counts) of the quadric through the poses v (N, 3)."""
    x, y, z = v.T
    ones = np.ones_like(x)
    if model == "six":
        design = np.column_stack([x * x, y * y, z * z, x, y, z, ones])
    else:
        design = np.column_stack(
            [x * x, y * y, z * z, 2 * x * y, 2 * x * z, 2 * y * z, x, y, z, ones]
        )
    # The full right factor, but never the N×N left one (only a few rows need it whole).
    q = np.linalg.svd(design, full_matrices=len(design) < design.shape[1])[2][-1]
    if model == "six":
        m = np.diag(q[:3])
        b, c = q[3:6], q[6]
    else:
        m = np.array([[q[0], q[3], q[4]], [q[3], q[1], q[5]], [q[4], q[5], q[2]]])
        b, c = q[6:9], q[9]
    try:
        offset = -0.5 * np.linalg.solve(m, b)
    except np.linalg.LinAlgError:
        raise NonPositiveScaleError(
            "no ellipsoid fits these poses: the quadric is singular"
        ) from None
    shape = m / (offset @ m @ offset - c)
    try:
        upper = np.linalg.cholesky(shape).T  # shape = UᵀU, U upper-triangular
    except np.linalg.LinAlgError:
        raise NonPositiveScaleError(
            "no ellipsoid fits these poses (a squared scale is not positive): a pose was not "
            "still, or poses are mislabelled"
        ) from None
    return offset, upper


def solve_least_squares(
    poses: FloatArray,
    model: Model = "six",
    limits: GeometryLimits = GeometryLimits(),
    max_condition: float = MAX_CONDITION,
) -> Solution:
    """Fit the ``model`` to N poses (N, 3) of mean counts; refuse with a clear message.

    Raises:
        TooFewPosesError: fewer poses than unknowns (6 or 9).
        CalibrationError: a screening finding, an ill-conditioned fit, no ellipsoid
            through the poses, or no convergence.
    """
    p = np.asarray(poses, dtype=np.float64)
    unknowns = UNKNOWNS[model]
    screened = check_poses(p, unknowns, limits)
    v = normalise(p)
    param = _Parametrisation(model)

    try:
        theta0 = pack(*algebraic_start(v, model), model)
    except NonPositiveScaleError:
        refuse_degenerate_geometry(v, model, max_condition)
        refuse_beyond_datasheet(p, limits.sensor)
        raise
    # Imported here: scipy.optimize takes ~0.5 s to load, and the server imports this
    # module at start while most six-pose runs never reach this solver.
    from scipy.optimize import least_squares

    fit = least_squares(param.residual, theta0, jac=param.jacobian, method="lm", args=(v,))
    if fit.status <= 0 or not np.all(np.isfinite(fit.x)):
        refuse_degenerate_geometry(v, model, max_condition)
        raise CalibrationError(
            f"the least-squares fit did not converge though the geometry is sound: {fit.message}"
        )
    offset_n, c_n = unpack(fit.x, model)
    if np.any(np.diag(c_n) <= 0):
        refuse_degenerate_geometry(v, model, max_condition)
        refuse_beyond_datasheet(p, limits.sensor)
        raise NonPositiveScaleError(
            "the fit found a non-positive scale though the geometry is sound: a pose was not still"
        )

    jac = param.jacobian(fit.x, v)
    condition = float(condition_number(jac))
    if not condition <= max_condition:
        # Sound poses whose fit lands on a degenerate solution: a pose no sensor could
        # read is the likelier cause, as for a non-positive scale.
        refuse_degenerate_geometry(v, model, max_condition)
        refuse_beyond_datasheet(p, limits.sensor)
        raise _degenerate(condition, model, max_condition)

    calibration = Calibration(
        model=model,
        offset=NOMINAL_OFFSET_COUNTS + NOMINAL_SENSITIVITY_COUNTS_PER_G * offset_n,
        matrix=c_n / NOMINAL_SENSITIVITY_COUNTS_PER_G,
    )
    s2 = calibration.sensitivity**2  # the paper's k1 = s_x²/s_y², k2 = s_x²/s_z²
    return Solution(
        calibration=calibration,
        method="least-squares",
        quality=quality_of(
            calibration, p, condition, screened, leverage(jac), limits.sensor.counts_per_g
        ),
        standard_errors=_standard_errors(jac, fit.fun, c_n, model),
        k=(float(s2[0] / s2[1]), float(s2[0] / s2[2])) if model == "six" else None,
    )


def _degenerate(condition: float, model: Model, max_condition: float) -> IllConditionedError:
    """The refusal of poses whose geometry does not determine the ``model``."""
    hint = (
        "add poses between the axes: the cross-axis terms need them"
        if model == "nine"
        else "spread the poses over more directions"
    )
    return IllConditionedError(
        f"pose geometry degenerate: the poses cannot determine the {model}-parameter model "
        f"(condition number {condition:.3g} > {max_condition:.3g}): {hint}"
    )


def refuse_degenerate_geometry(v: FloatArray, model: Model, max_condition: float) -> None:
    """Raise the geometry refusal when the poses v (N, 3) cannot determine the model even
    for the nominal sensor: a failed fit on such poses is their geometry's fault."""
    c = np.eye(3)
    offset = np.zeros(3)
    jac = jacobian_six(offset, np.ones(3), v) if model == "six" else jacobian_nine(offset, c, v)
    condition = float(condition_number(jac))
    if not condition <= max_condition:
        raise _degenerate(condition, model, max_condition)


def _standard_errors(
    jac: FloatArray, residual: FloatArray, c_n: FloatArray, model: Model
) -> CoefficientErrors | None:
    """σ̂²(JᵀJ)⁻¹ in counts; ``None`` without redundancy (N = p)."""
    n, p = jac.shape
    if n <= p:
        return None
    sigma2 = float(residual @ residual) / (n - p)
    cov = sigma2 * np.linalg.pinv(jac.T @ jac)
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None)) * NOMINAL_SENSITIVITY_COUNTS_PER_G
    if model == "six":
        return CoefficientErrors(offset=se[:3], sensitivity=se[3:6], dof=n - p)
    # sensitivity_j = 819.2 / C_jj (normalised): se = 819.2·se(C_jj)/C_jj²
    diag_index = [3, 6, 8]  # positions of C_00, C_11, C_22 in θ
    c_diag = np.diag(c_n)
    return CoefficientErrors(offset=se[:3], sensitivity=se[diag_index] / c_diag**2, dof=n - p)
