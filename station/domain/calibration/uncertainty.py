"""The uncertainty budget of every calibration coefficient ([JCGM100]_, the GUM).

Measurand: the offset o_j (counts) and sensitivity s_j (counts/g) of each accelerometer
axis at the conditions of the run, as the model defines them ([Song2006]_ eq. 5:
``s = 1/diag(C)``; for the nine-parameter model C is upper-triangular, x the reference
axis), and each gyro's bias b_j (deg/s) and gyro matrix K ([Tedaldi2014]_).

Model of the measurement. Every fitted still pose i sees 1 g::

    r_i(θ, a) = |C(θ)·(a_i − o)| − 1 = 0,        θ = (o, s) or (o, C_upper)

the fit solves it for θ in least squares (exactly, with six poses and eq. 10). To first
order a change δa of the pose means moves the coefficients by ([JCGM100]_ 5.1.2, the law
of propagation of uncertainty, through the fit's Jacobian J = ∂r/∂θ)::

    δθ = −J⁺ · δr,      δr_i = (Cᵀ n_i)ᵀ · δa_i,      n_i = C(a_i − o)/|C(a_i − o)|

so an independent uncertainty u(a_ij) of each pose mean gives the variances
``diag(G J⁺ W J⁺ᵀ Gᵀ)``, W = diag((Cᵀn_i)ᵀ Σ_i (Cᵀn_i)), G = ∂(o, s)/∂θ.

The budget's terms, each a standard uncertainty per coefficient (:data:`TERMS`):

``pose_noise``
    Type A: the spread of each pose's samples over the √ of their count,
    σ²_ij/N_i, less the quantisation's 1/12 LSB² that the spread already holds when the
    noise dithers the ADC (σ ≥ ½ LSB). Without the spread (a file of means only) the
    sensor's :data:`DEFAULT_SAMPLE_NOISE_COUNTS` over :data:`SAMPLES_PER_POSE` samples.
    A pose whose spread on an axis exceeds :data:`DISTURBED_SPREAD_RATIO` times the
    sensor's noise there (the median spread of the fitted poses, at least ½ LSB) was
    disturbed while it was taken (a knock, a hand on the jig): its samples are not one
    rest with white noise, and the excess moves the mean by up to its own size
    whatever the sample count (a step of height h over a fraction f of the samples adds
    f(1 − f)·h² to the variance and f·h to the mean, ≤ the excess's √ for f ≤ ½). That
    pose is de-weighted: its excess variance σ² − σ_noise² enters its mean's variance
    undivided by N_i, and it is named (:attr:`AccelerometerBudget.disturbed`).
``quantisation``
    Type B: the ADC's rounding, rectangular of width 1 LSB, LSB/√12 per sample; it
    averages down as 1/√N when the noise dithers it, not at all when σ < ½ LSB (then the
    mean is rounded as much as one sample).
``model``
    Type B: what the six-parameter model cannot represent. The sensor's cross-axis
    sensitivity, declared per sensor (``cross_axis_bound``: the product's
    :attr:`~station.domain.sensors.sensor_spec.SensorSpec.cross_axis`, ``calstation solve
    --cross-axis``; by default the KXM52-1050's :data:`CROSS_AXIS_BOUND`, 2 %,
    datasheet, [Song2006]_ Table 1), as a coupling matrix with each off-diagonal term
    rectangular within it; propagated by Monte Carlo ([JCGM101]_) over
    :data:`MODEL_DRAWS` seeded draws (a scrambled Sobol' sequence over the six terms:
    256 pseudo-random draws put the 95 % point of the sensitivities' change up to 9 %
    low, and the same draws serve every unit, so the error never averaged out: the
    sensitivities of datasheet-drawn units held on their axes were covered 92 % of the
    time; 1,024 Sobol' points put it within 1 %), each pose moved to
    ``o + diag(s)(I + M)·u_i`` and
    refitted (the coupling enters |g| in second order on
    the axis poses, so a first-order propagation would call it zero, and one-sided: it
    only ever raises the sensitivities there). The symmetric 95 % interval of the
    refitted coefficients' change, bias included ([JCGM101]_ 7.7), over k is the term.
    The fitted directions already carry the unit's own coupling; when every pose lies
    within the coupling's reach of an axis the sensitivities' term is taken along the
    axes, not along them (:func:`_model_term`: else it counted the coupling twice).
    The nine-parameter model represents the coupling: zero.
``fit``
    Type A, the evidence of the fit. With redundant poses (N > p): when the residuals'
    variance σ̂² = Σr²/(N − p) exceeds what the pose noise and quantisation explain
    beyond the χ² 95 % point, the excess times (JᵀJ)⁻¹; for the six-parameter model it
    is the same unmodelled effect as ``model``, so the larger of the two counts, once.
    A verification pose (held out of the fit) whose misfit |r_v| exceeds k times its
    predicted standard deviation scales ``model`` and ``fit`` by |r_v|/(k·u(r_v)).
``temperature``
    Type B: the drift of the sensor while its poses were taken. The coefficients are
    those at the mean temperature T̄ of the fitted poses; a pose taken at T_i reads
    ``δa_ij = (T_i − T̄)·(κ_o,j + κ_s,j·(a_ij − o_j))`` more, with the unit's temperature
    coefficients of offset κ_o (counts/°C) and sensitivity κ_s (/°C), unknown, rectangular
    within the sensor's datasheet bounds (the product's
    :class:`~station.domain.sensors.sensor_spec.SensorSpec`; the KXM52-1050's
    :data:`OFFSET_TEMPCO_BOUND`, :data:`SENSITIVITY_TEMPCO_BOUND` by default) and the
    same at every pose; propagated to first
    order through J⁺ as the pose noise is, linear in κ; the symmetric 95 % interval of
    the coefficients' change over :data:`TEMPCO_DRAWS` seeded draws of κ, over k
    ([JCGM101]_ 7.7: the change is near rectangular when one κ dominates, which k·σ would
    cover wholly); in θ's covariance each κ counts with its variance bound²/3
    ([JCGM100]_ 4.3.7). Zero when the poses' temperatures are all equal; when they are
    not known the drift is *excluded* and named so
    (:attr:`AccelerometerBudget.excluded_influences`, :data:`EXCLUDED_WHY`).
``tilt``
    Zero by construction, listed because a metrologist asks: the autocalibration uses
    only |g| = 1 at each pose, so the fixture's tilt does not enter ([Song2006]_); it
    enters the classic ±1 g method as s·(1 − cos θ) (:mod:`~.classic`), which no run
    uses.

Combined standard uncertainty u_c = √Σu² (the terms are independent), expanded
U = k·u_c with k = :data:`COVERAGE_FACTOR` (≈ 95 % for a normal distribution,
[JCGM100]_ 6.2). Validated by Monte Carlo on the simulator
(``benchmarks/bench_uncertainty.py``, ``docs/benchmarks.md``).

Matrix entries (:attr:`AccelerometerBudget.matrix`). The nine-parameter model's θ holds
the upper-triangular C itself (g/count; its off-diagonal entries are the axes'
misalignment and coupling, [Tedaldi2014]_), so each entry's U is k·√ of its diagonal
element of θ's covariance Σ_θ: the pose noise and quantisation through J⁺, the fit's
evidence (scaled, as its term is, by a verification ratio above 1) and the drift with
temperature, as every coefficient's. Its coverage is checked on simulated units with
known truth (:func:`station.simulator.coverage.simulate_coverage`, group ``matrix``).

Verification error (:attr:`AccelerometerBudget.verification_u`). The verification pose
a_v is held out of the fit; its error e_v = |r_v|, r_v = |C(θ)·(a_v − o)| − 1 (g; the
record's ``verification_error_mg`` is 1000·e_v), is the calibrated output's error at a
tilted pose. To first order::

    δr_v = J_v·δθ + (C^T n_v)^T·δa_v,        J_v = ∂r_v/∂θ

so its variance combines the calibrated output's uncertainty at that pose, J_v Σ_θ J_vᵀ
(the fit poses' noise and quantisation through θ = −J⁺δr, the fit's evidence, the
six-parameter model's misfit there from the ``model`` term's draws, and the drift with
temperature through θ together with the pose's own, the same κ), and the verification
pose's own noise and quantisation as each fitted pose's (``pose_noise``,
``quantisation``). For the six-parameter model the fit's evidence and the model's misfit
are one unmodelled effect: the larger counts. U(e_v) = k·u(r_v); it is not scaled by the
verification ratio, which is the error itself over it.

Gyro bias (:func:`gyro_bias_uncertainty`): the mean over the still poses; Type A the
within-pose noise σ/√(Σ N_i), or the poses' scatter s/√P where it exceeds that beyond
the χ² 95 % point (the scatter would also carry a g-dependent bias, which [Park2014]_
says a still unit has none of, or drift), plus the report's quantisation, 0.02 deg/s/√12
per sample, plus the sensor's declared turn-on to turn-on repeatability (Type B; when
none is declared it is named as excluded, :data:`EXCLUDED_WHY`). Gyro matrix K
(:func:`gyro_matrix_uncertainty`): Type A the fit's own standard errors
([Tedaldi2014]_: the moves' residuals, so the noise of each gravity direction and of the
integrated rates, and the integration's own error, as far as they
differ from move to move), and the moves' geometry: the accelerometer calibration the
gravity directions are computed with is uncertain too (the covariance of θ from the
pose noise, quantisation and the fit's evidence, :attr:`AccelerometerBudget.covariance`),
and its error turns every direction alike, which no residual shows; propagated to first
order through ∂u/∂θ and the fit's ∂K/∂u
(:attr:`station.domain.gyro.motion.GyroMatrixFit.direction_gain`). With the
six-parameter model, its unmodelled cross-axis coupling too (:func:`model_variance`):
each drawn coupling of the ``model`` term turns every gravity direction, through the
calibration it gives and the coupling itself.

.. [JCGM100] JCGM 100:2008, Evaluation of measurement data — Guide to the expression of
   uncertainty in measurement (GUM).
.. [JCGM101] JCGM 101:2008, Supplement 1 to the GUM — Propagation of distributions using
   a Monte Carlo method.
.. [Park2014] A Study on the G-Sensitivity Error of MEMS Vibratory Gyroscopes, 2014.
.. [Tedaldi2014] D. Tedaldi, A. Pretto, E. Menegatti, "A robust and easy to implement
   method for IMU calibration without external equipments", ICRA 2014.
"""

from dataclasses import dataclass, field, replace
from functools import cache, lru_cache
from typing import Final, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.domain.arrays import FloatArray
from station.domain.calibration.model import Model, xyz
from station.domain.calibration.residual import UPPER, pack, unpack
from station.domain.calibration.solution import Solution
from station.domain.sensors.sensor import (
    CROSS_AXIS_TYPICAL,
    GYRO_DPS_PER_LSB,
    OFFSET_TEMPCO_COUNTS_PER_C,
    SAMPLES_PER_POSE,
    SENSITIVITY_TEMPCO_PER_C,
)


class MoveFit(Protocol):
    """What the budget of the gyro matrix K reads of its fit from the moves
    ([Tedaldi2014]_; :class:`station.domain.gyro.motion.GyroMatrixFit`, whose package
    stands above this one): shapes as documented there."""

    @property
    def standard_errors(self) -> FloatArray: ...
    @property
    def directions(self) -> FloatArray: ...
    @property
    def direction_gain(self) -> FloatArray: ...


#: Coverage factor of every expanded uncertainty ([JCGM100]_ 6.2.1).
COVERAGE_FACTOR: Final = 2.0
#: One ADC count (the ADS7829's LSB); quantisation is rectangular over it.
ADC_LSB_COUNTS: Final = 1.0
#: The unmodelled cross-axis coupling of the six-parameter model: the KXM52-1050
#: datasheet's typical cross-axis sensitivity, 2 % ([Song2006]_ Table 1).
CROSS_AXIS_BOUND: Final = CROSS_AXIS_TYPICAL
#: The temperature coefficients' half-widths when no sensor is named: the KXM52-1050
#: datasheet's largest (:mod:`station.domain.sensors.sensor`), counts/°C and per °C.
OFFSET_TEMPCO_BOUND: Final = OFFSET_TEMPCO_COUNTS_PER_C
SENSITIVITY_TEMPCO_BOUND: Final = SENSITIVITY_TEMPCO_PER_C
#: A pose's sample noise when the file gives means only: the KXM52 at the stream's
#: bandwidth, ~2 counts RMS (``limits.toml``, pose_noise_counts).
DEFAULT_SAMPLE_NOISE_COUNTS: Final = 2.0
#: A pose's sample spread above this many times the sensor's noise on an axis (the median
#: spread of the fitted poses, at least ½ LSB) marks it disturbed: well beyond what the
#: spread of Gaussian noise does by chance (its relative standard deviation is
#: 1/√(2(N − 1)), 13 % at 30 samples, 2 % at 1024).
DISTURBED_SPREAD_RATIO: Final = 2.0
#: Seeded draws of the coupling matrix that propagate the model term (JCGM 101): the
#: points of a scrambled Sobol' sequence (a power of 2).
MODEL_DRAWS: Final = 1024
#: Seeded draws of the temperature coefficients that propagate the temperature term.
TEMPCO_DRAWS: Final = 4096
#: Gauss–Newton iterations of each draw's refit (its steps shrink ~100× each).
_REFITS: Final = 6
#: The largest condition number of a refit's normal matrix solved by LU (:func:`_refit`):
#: its step is then the pseudo-inverse's to within ~cond·ε (1e-8) of the step, far from
#: where the pseudo-inverse cuts (1e15), and the next step corrects what differs.
_SOLVE_CONDITION: Final = 1e8
#: Why an influence is left out of U when it is (``excluded_influences`` of a solve's
#: JSON): each named, never silently zero.
EXCLUDED_WHY: Final = {
    "temperature": "no temperature recorded at the poses (a temp_c column): the sensor's "
    "drift across them is not in U",
    "gyro_bias_repeatability": "no turn-on to turn-on repeatability of the gyro bias declared "
    "(--gyro-bias-repeatability): U holds this session's mean only",
}
#: The budget's terms, in the order they are listed.
TERMS: Final = ("pose_noise", "quantisation", "model", "fit", "temperature", "tilt")
_CHI2_QUANTILE: Final = 0.95
#: The coverage probability k = 2 stands for ([JCGM100]_ 6.2.2).
_COVERAGE_PROBABILITY: Final = 0.95


def chi2_quantile(df: int) -> float:
    """The χ² quantile :data:`_CHI2_QUANTILE` with ``df`` degrees of freedom, as
    ``scipy.stats.chi2.ppf`` computes it: twice the inverse of the regularised lower
    incomplete gamma function at ``df/2``. From ``scipy.special``, which the solve has
    loaded already: ``scipy.stats`` took ~1 s of the station's first unit to import."""
    from scipy.special import gammaincinv

    return 2.0 * float(gammaincinv(df / 2, _CHI2_QUANTILE))


@dataclass(frozen=True, eq=False)
class AccelerometerBudget:
    """Standard uncertainties of the accelerometer's coefficients, term by term.

    Attributes:
        terms: each of :data:`TERMS` → shape (6,): offset x, y, z (counts) and
            sensitivity x, y, z (counts/g), standard uncertainties.
        k: the coverage factor of :attr:`expanded`.
        verification_ratio: |r_v|/(k·u(r_v)) of the verification pose (``None`` without
            one); above 1 it scaled the ``model`` and ``fit`` terms.
        verification_u: the expanded uncertainty U (g) of the verification pose's error
            ||C(a_v − o)| − 1| (``None`` without one; module docstring, *Verification
            error*).
        matrix: shape (3, 3), the expanded uncertainty U (g/count) of each entry of the
            nine-parameter model's upper-triangular matrix C (zero below the diagonal;
            module docstring, *Matrix entries*); ``None`` for the six-parameter model,
            whose diagonal matrix the sensitivities' U states.
        theta, model: the fit's parameters θ ((o, s) or (o, C_upper)) and its model.
        covariance: shape (p, p), the covariance of θ from the pose noise, quantisation,
            the fit's evidence and the drift with temperature (the gravity directions'
            uncertainty for the gyro matrix, :func:`gyro_matrix_uncertainty`).
        model_draws: the six-parameter model's unmodelled coupling, draw by draw: the
            couplings I + M (K, 3, 3) and the θ (K, 6) the fit gives under each
            (:func:`_model_term`); ``None`` for the nine-parameter model.
        disturbed: the fitted poses (indices into the poses given, from 0) whose spread
            exceeds :data:`DISTURBED_SPREAD_RATIO` times the noise (module docstring,
            ``pose_noise``), de-weighted, each with its largest spread over the noise.
        excluded_influences: the influences not in U, by name (:data:`EXCLUDED_WHY`).
    """

    terms: dict[str, FloatArray]
    k: float = COVERAGE_FACTOR
    verification_ratio: float | None = None
    verification_u: float | None = None
    matrix: FloatArray | None = None
    theta: FloatArray | None = None
    model: Model = "six"
    covariance: FloatArray | None = None
    model_draws: tuple[FloatArray, FloatArray] | None = None
    disturbed: dict[int, float] = field(default_factory=dict)
    excluded_influences: tuple[str, ...] = ()

    @property
    def combined(self) -> FloatArray:
        """Shape (6,), the combined standard uncertainty u_c = √Σ u²."""
        squares = sum((values**2 for values in self.terms.values()), np.zeros(6))
        return np.asarray(np.sqrt(squares), dtype=np.float64)

    @property
    def expanded(self) -> FloatArray:
        """Shape (6,), U = k·u_c."""
        return np.asarray(self.k * self.combined, dtype=np.float64)

    @property
    def offset(self) -> FloatArray:
        """Shape (3,), expanded uncertainty of the offsets, counts."""
        return self.expanded[:3]

    @property
    def sensitivity(self) -> FloatArray:
        """Shape (3,), expanded uncertainty of the sensitivities, counts/g."""
        return self.expanded[3:]


@dataclass(frozen=True, eq=False)
class Uncertainty:
    """Expanded uncertainties (k = :attr:`k`) of a run's coefficients, the sensor's units.

    A coefficient the run has not measured is ``None`` (and absent from :meth:`to_dict`).
    """

    k: float = COVERAGE_FACTOR
    offset: FloatArray | None = None
    sensitivity: FloatArray | None = None
    gyro_bias_dps: FloatArray | None = None
    gyro_matrix: FloatArray | None = field(default=None)
    verification_error_mg: float | None = None
    matrix: FloatArray | None = None

    def to_dict(self) -> dict[str, object]:
        """``{"k", "offset": {x,y,z}, "sensitivity": {x,y,z}, "gyro_bias_dps": [3],
        "gyro_matrix": [[3×3]], "verification_error_mg", "matrix": [[3×3]]}``, keys of
        unmeasured coefficients left out."""
        out: dict[str, object] = {"k": self.k}
        if self.offset is not None:
            out["offset"] = xyz(self.offset)
        if self.sensitivity is not None:
            out["sensitivity"] = xyz(self.sensitivity)
        if self.gyro_bias_dps is not None:
            out["gyro_bias_dps"] = [float(v) for v in self.gyro_bias_dps]
        if self.gyro_matrix is not None:
            out["gyro_matrix"] = [[float(v) for v in row] for row in self.gyro_matrix]
        if self.verification_error_mg is not None:
            out["verification_error_mg"] = self.verification_error_mg
        if self.matrix is not None:
            out["matrix"] = [[float(v) for v in row] for row in self.matrix]
        return out

    @classmethod
    def of_budget(cls, budget: AccelerometerBudget) -> "Uncertainty":
        """The accelerometer's part, with its verification error's U in mg."""
        u = budget.verification_u
        return cls(
            k=budget.k,
            offset=budget.offset,
            sensitivity=budget.sensitivity,
            verification_error_mg=None if u is None else 1000.0 * u,
            matrix=budget.matrix,
        )

    def with_gyro(
        self, bias_dps: FloatArray | None, matrix: FloatArray | None = None
    ) -> "Uncertainty":
        """The same with the gyros' expanded uncertainties added."""
        return replace(self, gyro_bias_dps=bias_dps, gyro_matrix=matrix)


def accelerometer_budget(
    solution: Solution,
    poses: ArrayLike,
    spread: ArrayLike | None = None,
    samples: ArrayLike | None = None,
    *,
    verification: ArrayLike | None = None,
    verification_spread: ArrayLike | None = None,
    verification_samples: int | None = None,
    temperatures: ArrayLike | None = None,
    verification_temperature: float | None = None,
    tempco: tuple[float, float] = (OFFSET_TEMPCO_BOUND, SENSITIVITY_TEMPCO_BOUND),
    cross_axis_bound: float = CROSS_AXIS_BOUND,
    k: float = COVERAGE_FACTOR,
) -> AccelerometerBudget:
    """The budget of ``solution``'s coefficients (module docstring).

    Args:
        solution: the solve of ``poses``.
        poses: shape (N, 3), the mean counts the solve was given (excluded poses too).
        spread: shape (N, 3), each pose's sample standard deviation, counts (``None``:
            :data:`DEFAULT_SAMPLE_NOISE_COUNTS`).
        samples: shape (N,), samples per pose (``None``: :data:`SAMPLES_PER_POSE`).
        verification: shape (3,), the verification pose's mean counts, if one was held out.
        verification_spread, verification_samples: its spread and sample count.
        temperatures: shape (N,), each pose's temperature, °C (``None``: not known, no
            temperature term).
        verification_temperature: the verification pose's, °C.
        tempco: the half-widths of the sensor's temperature coefficients of offset
            (counts/°C) and sensitivity (/°C), its datasheet's
            (:attr:`~station.domain.sensors.sensor_spec.SensorSpec.offset_tempco_counts_per_c`;
            the default is the putter's KXM52).
        cross_axis_bound: the unmodelled coupling's half-width (six-parameter model).
        k: the coverage factor.
    """
    a_all = np.asarray(poses, dtype=np.float64)
    n_all = len(a_all)
    keep = np.setdiff1d(np.arange(n_all), np.asarray(solution.excluded, dtype=np.int64))
    a = a_all[keep]
    var_noise, var_quant = _pose_variances(spread, samples, n_all)
    var_noise, var_quant = var_noise[keep], var_quant[keep]
    disturbed: dict[int, float] = {}
    if spread is not None:
        excess, disturbed = disturbed_poses(
            np.asarray(spread, dtype=np.float64).reshape(n_all, 3), keep
        )
        var_noise = var_noise + excess

    cal = solution.calibration
    model = cal.model
    theta = pack(cal.offset, cal.matrix, model)  # in counts; C_upper in g/count
    offset, c = unpack(theta, model)
    jac, dr_da, n = _jacobians(theta, a, model)
    scale = np.linalg.norm(jac, axis=0)
    scale[scale == 0] = 1.0
    pinv = np.linalg.pinv(jac / scale) / scale[:, None]  # J⁺, p × N
    g = _output_jacobian(theta, model)  # 6 × p
    gp = g @ pinv  # 6 × N: δy = −gp · δr

    w_noise = np.einsum("ij,ij->i", dr_da**2, var_noise)
    w_quant = np.einsum("ij,ij->i", dr_da**2, var_quant)
    covariance = (pinv * (w_noise + w_quant)) @ pinv.T
    terms = {name: np.zeros(6) for name in TERMS}  # tilt stays zero (module docstring)
    terms["pose_noise"] = np.sqrt(gp**2 @ w_noise)
    terms["quantisation"] = np.sqrt(gp**2 @ w_quant)
    drift: FloatArray | None = None  # ∂r/∂κ of the fit poses
    reference = 0.0  # the calibration's temperature T̄, °C
    kappa_bound = np.repeat(tempco, 3)
    kappa_variance = kappa_bound**2 / 3  # rectangular within the datasheet's bounds
    if temperatures is not None:
        t = np.asarray(temperatures, dtype=np.float64).reshape(n_all)[keep]
        reference = float(np.mean(t))
        drift = _drift_jacobian(theta, model, a, dr_da, t - reference)
        terms["temperature"] = _temperature_term(gp @ drift, kappa_bound)
        covariance = covariance + (pinv @ drift * kappa_variance) @ (pinv @ drift).T
    model_rv: FloatArray | None = None
    model_draws: tuple[FloatArray, FloatArray] | None = None
    u_dir: FloatArray | None = None
    if verification is not None:
        av = np.asarray(verification, dtype=np.float64)
        gv = c @ (av - offset)
        u_dir = gv / np.linalg.norm(gv)
    if model == "six" and cross_axis_bound > 0:
        terms["model"], model_rv, model_draws = _model_term(theta, n, g, cross_axis_bound, u_dir)

    # The evidence of the residuals (redundant fits only).
    evidence: FloatArray | None = None  # its covariance of θ
    rows, p = jac.shape
    if rows > p:
        residual = np.linalg.norm((a - offset) @ c.T, axis=1) - 1.0
        sigma2 = float(residual @ residual) / (rows - p)
        expected = float(np.mean(w_noise + w_quant))
        if drift is not None:  # what the drift leaves in the residuals, (I − J·J⁺)·D·κ
            left = drift - jac @ (pinv @ drift)
            expected += float(np.sum(left**2 @ kappa_variance)) / (rows - p)
        if sigma2 > expected * chi2_quantile(rows - p) / (rows - p):
            cov = np.linalg.pinv((jac / scale).T @ (jac / scale)) / np.outer(scale, scale)
            evidence = cov * (sigma2 - expected)
            covariance = covariance + evidence
            terms["fit"] = np.sqrt(
                np.clip(np.einsum("ij,jk,ik->i", g, cov, g), 0.0, None) * (sigma2 - expected)
            )
        if model == "six":
            worst = np.maximum(terms["model"], terms["fit"])
            terms["model"], terms["fit"] = worst, np.zeros(6)

    ratio: float | None = None
    verification_u: float | None = None
    if verification is not None and u_dir is not None:
        av = np.asarray(verification, dtype=np.float64)
        jv, dv, _ = _jacobians(theta, av[None, :], model)
        var_temperature = 0.0
        if drift is not None and verification_temperature is not None:
            # Its drift through θ and its own, the same κ: δr_v = (D_v − J_v·J⁺·D)·κ.
            delta_v = np.array([verification_temperature - reference])
            row = _drift_jacobian(theta, model, av[None, :], dv, delta_v)[0]
            row = row - (jv @ pinv @ drift)[0]
            var_temperature = float(row**2 @ kappa_variance)
        # Its misfit r_v = |C(a_v − o)| − 1 (g) and predicted variance (g²): δr_v = J_v δθ +
        # ∂r_v/∂a_v δa_v with δθ = −J⁺ δr, so the fit poses' noise reaches it through θ; its
        # own noise and quantisation; the model's misfit there; the drift with temperature.
        rv = float(np.linalg.norm(c @ (av - offset)) - 1.0)
        var_fit = float((jv @ pinv)[0] ** 2 @ (w_noise + w_quant))
        var_n, var_q = _pose_variances(verification_spread, verification_samples, 1)
        var_own = float(dv[0] ** 2 @ (var_n[0] + var_q[0]))
        var_model = 0.0 if model_rv is None else float(np.mean(model_rv**2))
        predicted = var_fit + var_own + var_model + var_temperature
        ratio = abs(rv) / (k * np.sqrt(predicted)) if predicted > 0 else float("inf")
        # The fit's evidence (its covariance of θ beyond the noise's) there: J_v Σ J_vᵀ.
        evidence_v = 0.0 if evidence is None else max(0.0, float((jv @ evidence @ jv.T)[0, 0]))
        # The fit's evidence and the model's misfit are one unmodelled effect for the
        # six-parameter model: the larger counts, once (as for the coefficients).
        beyond = max(0.0, evidence_v - var_model)
        verification_u = float(k * np.sqrt(predicted + beyond))
        if ratio > 1.0:
            terms["model"] = terms["model"] * ratio
            terms["fit"] = terms["fit"] * ratio
    matrix_u: FloatArray | None = None
    if model == "nine":
        # The fit's evidence, scaled as its term is by a verification ratio above 1.
        scaled = covariance
        if evidence is not None and ratio is not None and ratio > 1.0:
            scaled = covariance + evidence * (ratio**2 - 1.0)
        matrix_u = np.zeros((3, 3))
        matrix_u[UPPER] = k * np.sqrt(np.clip(np.diag(scaled)[3:9], 0.0, None))
    return AccelerometerBudget(
        terms={name: np.asarray(terms[name], dtype=np.float64) for name in TERMS},
        k=k,
        verification_ratio=ratio,
        verification_u=verification_u,
        matrix=matrix_u,
        theta=theta,
        model=model,
        covariance=covariance,
        model_draws=model_draws,
        disturbed=disturbed,
        excluded_influences=() if temperatures is not None else ("temperature",),
    )


def gyro_bias_repeatability(session_biases_dps: ArrayLike) -> FloatArray:
    """The gyro bias' turn-on to turn-on repeatability (3,) measured across S ≥ 2
    power-on sessions of one unit (``session_biases_dps`` (S, 3), each session's bias,
    deg/s): the sessions' sample standard deviation per axis, Type A with S − 1 degrees of
    freedom ([JCGM100]_ 4.2.2, B.2.15: the same unit measured after a change of
    condition, its power cycled). Each session's mean carries its own within-session
    noise too, which is orders smaller than a MEMS gyro's turn-on spread and is left in.

    Raises:
        ValueError: fewer than two sessions.
    """
    biases = np.asarray(session_biases_dps, dtype=np.float64)
    if biases.ndim != 2 or len(biases) < 2:
        raise ValueError("the bias repeatability needs at least two sessions")
    return np.asarray(np.std(biases, axis=0, ddof=1), dtype=np.float64)


def gyro_bias_uncertainty(
    pose_means_dps: ArrayLike,
    spread_dps: ArrayLike | None = None,
    samples: ArrayLike | None = None,
    k: float = COVERAGE_FACTOR,
    repeatability_dps: float | FloatArray = 0.0,
) -> FloatArray:
    """Expanded uncertainty (3,) of the gyro bias, the mean of the still poses' means (P, 3).

    ``repeatability_dps``: the turn-on to turn-on repeatability of the bias (a standard
    deviation, deg/s, one for all axes or one per axis): declared by the sensor (Type B,
    [JCGM100]_ 4.3) or measured across power-on sessions
    (:func:`gyro_bias_repeatability`, Type A). One session's mean does not show how the
    bias moves at the next power-on, so it is added in quadrature.

    Type A: the pooled within-pose noise σ/√ΣN_i (``spread_dps`` (P, 3) and ``samples``
    (P,) when known), or the poses' scatter s/√P where it exceeds that beyond the χ²
    95 % point (a bias that moves between poses); without spreads the scatter. Type B: the report's
    quantisation :data:`~station.domain.sensors.sensor.GYRO_DPS_PER_LSB`/√12 per sample, averaged
    as the accelerometer's (module docstring).
    """
    means = np.asarray(pose_means_dps, dtype=np.float64)
    p = len(means)
    if p < 1:
        raise ValueError("the gyro bias needs at least one still pose")
    counts = (
        np.full(p, float(SAMPLES_PER_POSE))
        if samples is None
        else np.asarray(samples, dtype=np.float64)
    )
    total = float(np.sum(counts))
    lsb2 = GYRO_DPS_PER_LSB**2 / 12.0
    if spread_dps is None:
        within = np.zeros(3)
        quant = np.full(3, np.sqrt(lsb2 / total))
    else:
        sd = np.asarray(spread_dps, dtype=np.float64)
        dithered = sd >= GYRO_DPS_PER_LSB / 2
        noise2 = np.where(dithered, np.clip(sd**2 - lsb2, 0.0, None), sd**2)
        within = np.sqrt(np.sum(noise2 * counts[:, None], axis=0)) / total
        per_pose_q = np.where(dithered, lsb2 / counts[:, None], lsb2)
        quant = np.sqrt(np.sum(per_pose_q, axis=0)) / p
    type_a = within
    if p > 1:
        scatter = np.std(means, axis=0, ddof=1) / np.sqrt(p)
        beyond = scatter**2 > within**2 * chi2_quantile(p - 1) / (p - 1)
        type_a = np.where(beyond, scatter, within)
    u = np.sqrt(type_a**2 + quant**2 + repeatability_dps**2)
    return np.asarray(k * u, dtype=np.float64)


def gyro_matrix_uncertainty(
    fit: MoveFit, budget: AccelerometerBudget | None, k: float = COVERAGE_FACTOR
) -> FloatArray:
    """Expanded uncertainty (3, 3) of each element of the gyro matrix K (module docstring):
    k·√(max(u_fit², u_model²) + u_geometry²), u_fit the fit's standard errors
    ([Tedaldi2014]_), u_model the six-parameter model's unmodelled coupling carried into K
    through the gravity directions (:func:`model_variance`; the residuals hold part of it,
    so the larger of the two counts), u_geometry the accelerometer calibration's
    covariance carried the same way (``budget`` None: the fit's term alone).
    [JCGM100]_ 5.1.2."""
    variance = fit.standard_errors**2
    if budget is not None:
        variance = np.maximum(variance, model_variance(fit, budget))
        variance = variance + geometry_variance(fit, budget)
    return np.asarray(k * np.sqrt(variance), dtype=np.float64)


def model_variance(fit: MoveFit, budget: AccelerometerBudget) -> FloatArray:
    """Variance (3, 3) of K from the six-parameter model's unmodelled cross-axis coupling
    (zero for the nine-parameter model, which represents it). Under each drawn coupling M
    of the accelerometer's ``model`` term a move's end along u reads
    ``a = o + diag(s)(I + M)·u`` and the fit gives θ_M; the gravity direction computed
    from it, ``diag(1/s_M)(a − o_M)`` normalised, is off u by δu, the same M at every
    move, and K by ∂K/∂u·δu (:attr:`~station.domain.gyro.motion.GyroMatrixFit.direction_gain`).
    As the ``model`` term: the symmetric 95 % interval of δK over the draws, over k
    ([JCGM101]_ 7.7), squared."""
    if budget.model_draws is None or budget.theta is None:
        return np.zeros((3, 3))
    coupled, thetas = budget.model_draws
    offset, s = budget.theta[:3], budget.theta[3:6]
    ends = fit.directions.reshape(-1, 3)  # (2M, 3)
    counts = offset + np.einsum("kij,nj->kni", coupled, ends) * s  # (K, 2M, 3)
    seen = (counts - thetas[:, None, :3]) / thetas[:, None, 3:6]
    seen /= np.linalg.norm(seen, axis=2, keepdims=True)
    moved = np.einsum(
        "an,kn->ka", fit.direction_gain.reshape(9, -1), (seen - ends).reshape(len(seen), -1)
    )
    u = np.quantile(np.abs(moved), _COVERAGE_PROBABILITY, axis=0) / COVERAGE_FACTOR
    return np.asarray((u**2).reshape(3, 3), dtype=np.float64)


def geometry_variance(fit: MoveFit, budget: AccelerometerBudget) -> FloatArray:
    """Variance (3, 3) of K from the accelerometer calibration's error (the moves'
    geometry): each gravity direction u = C(a − o)/|C(a − o)| of a move's end moves by
    ∂u/∂θ·δθ, the same δθ for every move, so ``var(K) = diag(A Σ_θ Aᵀ)`` with
    A = ∂K/∂u · ∂u/∂θ. A move's end in counts is ``a = o + C⁻¹u`` (|g| = 1 at rest); ∂u/∂θ
    by central differences of one thousandth of each θ's standard uncertainty. Zero
    without θ's covariance."""
    if budget.theta is None or budget.covariance is None:
        return np.zeros((3, 3))
    theta, cov = budget.theta, budget.covariance
    offset, c = unpack(theta, budget.model)
    ends = fit.directions.reshape(-1, 3)
    counts = offset + np.linalg.solve(c, ends.T).T  # (2M, 3)

    def directions(t: FloatArray) -> FloatArray:
        o, m = unpack(t, budget.model)
        g = (counts - o) @ m.T
        return np.asarray(g / np.linalg.norm(g, axis=1, keepdims=True), dtype=np.float64)

    steps = 1e-3 * np.sqrt(np.clip(np.diag(cov), 0.0, None))
    du = np.zeros((ends.size, len(theta)))
    for m, h in enumerate(steps):
        if h == 0.0:
            continue
        e = np.zeros(len(theta))
        e[m] = h
        du[:, m] = ((directions(theta + e) - directions(theta - e)) / (2 * h)).ravel()
    a = fit.direction_gain.reshape(9, -1) @ du  # (9, p)
    return np.asarray(
        np.clip(np.einsum("ij,jk,ik->i", a, cov, a), 0.0, None).reshape(3, 3), dtype=np.float64
    )


def _drift_jacobian(
    theta: FloatArray, model: Model, a: FloatArray, dr_da: FloatArray, delta: FloatArray
) -> FloatArray:
    """∂r/∂κ (N, 6) of poses a (N, 3) taken ``delta`` (N,) °C from the calibration's
    temperature, κ = (κ_o, κ_s) the temperature coefficients (module docstring,
    ``temperature``): δa_ij = Δ_i·(κ_o,j + κ_s,j·(a_ij − o_j)), δr_i = (∂r_i/∂a_i)·δa_i."""
    offset, _ = unpack(theta, model)
    return np.hstack([dr_da * delta[:, None], dr_da * (a - offset) * delta[:, None]])


def _temperature_term(gain: FloatArray, bound: FloatArray) -> FloatArray:
    """The temperature term (6,) from ∂y/∂κ (6, 6): the symmetric 95 % interval of
    ``gain·κ`` over :data:`TEMPCO_DRAWS` seeded draws of κ, rectangular within the
    datasheet's bounds ``bound`` (6,), over k ([JCGM101]_ 7.7: where one rectangular κ
    dominates a coefficient, k·σ would cover all of it, not 95 %)."""
    kappa = _tempco_draws() * bound
    shift = np.abs(kappa @ gain.T)
    return np.asarray(
        np.quantile(shift, _COVERAGE_PROBABILITY, axis=0) / COVERAGE_FACTOR, dtype=np.float64
    )


@cache
def _tempco_draws() -> FloatArray:
    """The temperature term's :data:`TEMPCO_DRAWS` seeded draws (K, 6), rectangular in ±1;
    drawn once and kept read-only: a budget is due at the end of every unit."""
    draws = np.random.default_rng(20080903).uniform(-1.0, 1.0, (TEMPCO_DRAWS, 6))
    draws.flags.writeable = False
    return draws


def _pose_variances(
    spread: ArrayLike | None, samples: ArrayLike | None, n: int
) -> tuple[FloatArray, FloatArray]:
    """Per pose and axis (N, 3): variance of the mean from noise, and from quantisation."""
    counts = (
        np.full(n, float(SAMPLES_PER_POSE))
        if samples is None
        else np.asarray(samples, dtype=np.float64).reshape(n)
    )
    sd = (
        np.full((n, 3), DEFAULT_SAMPLE_NOISE_COUNTS)
        if spread is None
        else np.asarray(spread, dtype=np.float64).reshape(n, 3)
    )
    lsb2 = ADC_LSB_COUNTS**2 / 12.0
    dithered = sd >= ADC_LSB_COUNTS / 2
    noise = np.where(dithered, np.clip(sd**2 - lsb2, 0.0, None), sd**2) / counts[:, None]
    quant = np.where(dithered, lsb2 / counts[:, None], lsb2)
    return np.asarray(noise, dtype=np.float64), np.asarray(quant, dtype=np.float64)


def disturbed_poses(spread: ArrayLike, fitted: ArrayLike) -> tuple[FloatArray, dict[int, float]]:
    """The poses disturbed while they were taken (module docstring, ``pose_noise``): of
    the poses' sample spreads ``spread`` (N, 3), counts, those of the ``fitted`` poses
    (indices) whose spread σ on an axis exceeds :data:`DISTURBED_SPREAD_RATIO` times the
    sensor's noise there, σ_noise the median spread of the fitted poses (at least ½ LSB).
    Returns the fitted poses' excess variance (len(fitted), 3), counts²: σ² − σ_noise²
    where disturbed, else 0 (what a disturbed pose's mean carries beyond its noise's); and
    the disturbed poses (index into ``spread``) with their largest σ/σ_noise
    (:attr:`AccelerometerBudget.disturbed`)."""
    keep = np.asarray(fitted, dtype=np.int64)
    sd = np.asarray(spread, dtype=np.float64)[keep]
    noise = np.maximum(np.median(sd, axis=0), ADC_LSB_COUNTS / 2)
    excess = np.where(sd > DISTURBED_SPREAD_RATIO * noise, sd**2 - noise**2, 0.0)
    over_noise = np.max(sd / noise, axis=1)
    found = np.flatnonzero(np.any(excess > 0, axis=1))
    return excess, {int(keep[i]): float(over_noise[i]) for i in found}


def _jacobians(theta: FloatArray, a: FloatArray, model: Model) -> tuple[FloatArray, ...]:
    """J = ∂r/∂θ (N, p), ∂r_i/∂a_i (N, 3) and the unit calibrated gravity n (N, 3)."""
    offset, c = unpack(theta, model)
    d = a - offset
    gvec = d @ c.T
    n = gvec / np.linalg.norm(gvec, axis=1, keepdims=True)
    dr_da = n @ c
    if model == "six":
        s = theta[3:6]
        tail = -n * d / s**2
    else:
        tail = n[:, UPPER[0]] * d[:, UPPER[1]]
    return np.hstack([-dr_da, tail]), dr_da, n


def _output_jacobian(theta: FloatArray, model: Model) -> FloatArray:
    """G = ∂(o, s)/∂θ, shape (6, p)."""
    if model == "six":
        return np.eye(6)
    g = np.zeros((6, 9))
    g[:3, :3] = np.eye(3)
    for axis, column in enumerate((3, 6, 8)):  # C_00, C_11, C_22 in θ
        g[3 + axis, column] = -1.0 / theta[column] ** 2
    return g


def _residuals(theta: FloatArray, a: FloatArray) -> FloatArray:
    """Six-parameter residuals for K parameter sets θ (K, 6) and poses a (K, N, 3)."""
    g = (a - theta[:, None, :3]) / theta[:, None, 3:6]
    return np.asarray(np.linalg.norm(g, axis=2) - 1.0, dtype=np.float64)


def _refit(theta: FloatArray, poses: FloatArray) -> FloatArray:
    """Six-parameter Gauss–Newton fits (K, 6) of K pose sets (K, N, 3), from θ.

    Each step solves the normal equations JᵀJ·δ = Jᵀr. A budget is due at the end of
    every unit, so a set whose JᵀJ is provably well conditioned
    (:func:`_well_conditioned`) is solved by LU (``np.linalg.solve``): the same step as
    the pseudo-inverse's to rounding, for a tenth of its CPU; any other set keeps the
    pseudo-inverse's least-norm step, which a singular set needs.
    """
    thetas = np.repeat(theta[None, :], len(poses), axis=0)
    weyl: tuple[FloatArray, FloatArray] | None = None  # a reference JᵀJ, its eigenvalues
    for _ in range(_REFITS):
        s = thetas[:, None, 3:6]
        g = (poses - thetas[:, None, :3]) / s
        norm = np.linalg.norm(g, axis=2, keepdims=True)
        slope = g / norm / s  # n/s
        jac = np.concatenate([slope, slope * g], axis=2)  # −J (K, N, 6)
        jac_t = jac.transpose(0, 2, 1)
        normal = jac_t @ jac
        rhs = jac_t @ (norm - 1.0)  # −Jᵀr (K, 6, 1)
        if weyl is None:  # the draws' mean at the start: each draw's lies close to it
            centre = normal.mean(axis=0)
            weyl = (centre, np.linalg.eigvalsh(centre))
        well = _well_conditioned(normal, *weyl)
        step = np.empty_like(rhs)
        step[well] = np.linalg.solve(normal[well], rhs[well])
        if not well.all():
            step[~well] = np.linalg.pinv(normal[~well]) @ rhs[~well]
        thetas = thetas + step[..., 0]
    return thetas


def _well_conditioned(
    normal: FloatArray, reference: FloatArray, eigenvalues: FloatArray
) -> NDArray[np.bool_]:
    """Which normal matrices (K, 6, 6) have a condition number within
    :data:`_SOLVE_CONDITION`, by Weyl's inequality about a ``reference`` (6, 6) of known
    ``eigenvalues``: every eigenvalue of A moves by at most ‖A − R‖₂ ≤ ‖A − R‖_F. Rows
    that are not finite are not."""
    distance = np.sqrt(np.sum((normal - reference) ** 2, axis=(1, 2)))
    smallest, largest = eigenvalues[0] - distance, eigenvalues[-1] + distance
    return np.asarray(smallest * _SOLVE_CONDITION > largest, dtype=np.bool_)


@lru_cache(maxsize=8)
def _couplings(bound: float) -> FloatArray:
    """:data:`MODEL_DRAWS` couplings I + M (K, 3, 3), M's six off-diagonal terms
    rectangular ±bound, from a scrambled Sobol' sequence (``scipy.stats.qmc``: the 95 %
    point of the coefficients' change within 1 % of its limit, where as many
    pseudo-random draws miss it by up to 4 %); the same draws every time (a budget is a
    function of its inputs). Drawn once per bound and kept read-only: a budget is due
    at the end of every unit."""
    from scipy.stats import qmc

    points = qmc.Sobol(6, scramble=True, seed=20080901).random(MODEL_DRAWS)
    m = np.zeros((MODEL_DRAWS, 3, 3))
    m[:, ~np.eye(3, dtype=bool)] = (2.0 * points - 1.0) * bound
    coupled = np.eye(3) + m
    coupled.flags.writeable = False
    return coupled


def _along_axes(n: FloatArray, bound: float) -> FloatArray | None:
    """The poses' axes (N, 3) when every fitted direction n_i lies within what the unit's
    own coupling can do to a pose along an axis, else ``None``.

    A coupling M with off-diagonal terms within ±bound turns a true direction u into
    ∝ (I + M)·u, which moves component j by at most bound·Σ_{k≠j}|u_k|: a pose whose
    every off-axis component is within that reach cannot be told from a pose exactly
    along its axis that the coupling skewed.
    """
    magnitude = np.abs(n)
    reach = bound * (magnitude.sum(axis=1, keepdims=True) - magnitude)
    axis = np.argmax(magnitude, axis=1)
    off = np.ones_like(n, dtype=bool)
    off[np.arange(len(n)), axis] = False
    if np.any(magnitude[off] > reach[off]):
        return None
    axes = np.zeros_like(n)
    axes[np.arange(len(n)), axis] = np.sign(n[np.arange(len(n)), axis])
    return axes


def _coupling_shifts(
    theta: FloatArray, directions: FloatArray, g: FloatArray, coupled: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The coefficients' changes (K', 6) when the poses o + diag(s)(I + M)·d_i along
    ``directions`` d (N, 3) are refitted, one row per coupling (I + M) of ``coupled``
    (K, 3, 3) that refits; and those refits' θ and couplings."""
    offset, s = theta[:3], theta[3:6]
    moved = offset + np.einsum("kij,nj->kni", coupled, directions) * s  # (K, N, 3)
    thetas = _refit(theta, moved)
    shift = (thetas - theta) @ g.T
    solved = np.all(np.isfinite(shift), axis=1) & np.all(thetas[:, 3:] > 0, axis=1)
    return shift[solved], thetas[solved], coupled[solved]


def _model_term(
    theta: FloatArray,
    n: FloatArray,
    g: FloatArray,
    bound: float,
    verification_dir: FloatArray | None,
) -> tuple[FloatArray, FloatArray | None, tuple[FloatArray, FloatArray] | None]:
    """The model term (6,), with a verification pose the misfit (K,) the coupling leaves
    on it, and the draws (the couplings I + M and the refitted θ,
    :attr:`AccelerometerBudget.model_draws`).

    For each drawn coupling M the poses ``o + diag(s)(I + M)·n_i`` along the fitted
    directions n_i are refitted with the six-parameter model (Gauss–Newton from the fit);
    the change of the coefficients is what M does to them. The fitted directions carry the
    unit's own coupling c too, which the data cannot tell from the pose's tilt t. The
    offsets move in first order, with t·M, and the c in n_i stands in for the tilt the
    data cannot show: their term is taken along n_i. The sensitivities of poses along the
    axes move in second order only, with |M|²/2, and along n_i = t + c the draw adds a
    cross term c·M the unit does not have, twice the right term there
    (``docs/benchmarks.md``); so when every pose lies within the coupling's reach of its
    axis (:func:`_along_axes`) the sensitivities' term is taken along the axes.
    """
    offset, s = theta[:3], theta[3:6]
    shift, thetas, coupled = _coupling_shifts(theta, n, g, _couplings(bound))
    if len(shift) == 0:  # no draw refits: the coupling's own bound on every coefficient
        return np.asarray(np.concatenate([s, s]) * bound, dtype=np.float64), None, None
    # JCGM 101 7.7: the symmetric 95 % interval of the (biased: one-sided on the axis
    # poses) changes, as the standard uncertainty that k turns back into it.
    term = np.quantile(np.abs(shift), _COVERAGE_PROBABILITY, axis=0) / COVERAGE_FACTOR
    axes = _along_axes(n, bound)
    if axes is not None:
        along, _, _ = _coupling_shifts(theta, axes, g, _couplings(bound))
        if len(along):
            term[3:] = np.quantile(np.abs(along[:, 3:]), _COVERAGE_PROBABILITY, axis=0)
            term[3:] /= COVERAGE_FACTOR
    term = np.asarray(term, dtype=np.float64)
    if verification_dir is None:
        return term, None, (coupled, thetas)
    av = offset + np.einsum("kij,j->ki", coupled, verification_dir) * s
    rv = _residuals(thetas, av[:, None, :])[:, 0]
    return term, np.asarray(rv, dtype=np.float64), (coupled, thetas)
