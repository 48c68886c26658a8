"""Monte Carlo check of the uncertainty budget ([JCGM101]_): simulated units with known
truth, run through each profile's poses, solve and budget; does the truth lie within ±U?

Each unit is drawn as the line meets them (:meth:`SensorTruth.draw`: datasheet spreads,
2 % cross-axis coupling, 1 count noise), at the reference temperature (its truth is
defined there), or with its poses taken as the board warms from power-up
(``pose_interval_s``, :func:`simulate_coverage`). Each of the profile's poses
(``RunSettings``: the six of [Song2006]_ and the verification pose, or the whole unit's
twelve) is a window of ``window_samples`` samples, rounded by the ADC; the jig places
each pose off its nominal direction by up to ``tilt_deg`` (uniform, about a random
axis). The pose means, spreads and counts go to :func:`station.domain.calibration.solve` and
:func:`station.domain.calibration.uncertainty.accelerometer_budget` exactly as a run's
do, the gyro pose means to :func:`~station.domain.calibration.uncertainty.gyro_bias_uncertainty`.

The truth compared with: the offsets, and the sensitivities as the model defines them
(six: each axis' own counts/g, ``diag(S)``; nine: ``1/diag(C)`` of the upper-triangular
C with ``C = Q·S⁻¹``), the gyro biases, and for the nine-parameter model C's entries above
its diagonal (group :data:`MATRIX`).

The gyro matrix K (:func:`simulate_gyro_matrix_coverage`): a whole unit's stream, sample
by sample (:mod:`station.simulator.recording`: K with ±1 % scale and ±0.5 % misalignment,
2 % accelerometer cross-axis coupling, 500 samples/s, minimum-jerk turns with a wobble)
over the profile's poses, each turned about the vertical at random, through
:func:`station.domain.gyro.motion.calibrate_stream` (stills, accelerometer, bias, K and
their budgets, as ``solve --stream`` does); K's truth is the simulator's in the
calibrated accelerometer's frame (:func:`~station.simulator.recording.k_in_calibrated_frame`).
"""

from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial.transform import Rotation

from station.domain.arrays import FloatArray
from station.domain.calibration import CalibrationError, Model, solve
from station.domain.calibration.uncertainty import (
    CROSS_AXIS_BOUND,
    accelerometer_budget,
    gyro_bias_uncertainty,
)
from station.domain.constants import DEFAULT_RATE_HZ
from station.domain.gyro.motion import calibrate_stream
from station.domain.product.run_settings import RunSettings, shipped_plan
from station.domain.sensors.sensor import (
    ADC_MAX,
    ADC_MIN,
    GYRO_DPS_PER_LSB,
    OFFSET_TEMPCO_COUNTS_PER_C,
    SENSITIVITY_TEMPCO_PER_C,
)
from station.domain.signals.poses import POSES
from station.simulator.recording import (
    k_in_calibrated_frame,
    pose_orientations,
    random_imu,
    recorded_stream,
)
from station.simulator.sensor import REFERENCE_TEMPERATURE_C, SensorTruth, Thermal

#: The coefficient groups a coverage is counted over.
GROUPS = ("offset", "sensitivity", "gyro_bias")
#: The nine-parameter model's off-diagonal entries of C (its misalignment and coupling),
#: counted apart (:attr:`Coverage.checked` ``"matrix"``; not in :meth:`Coverage.fraction`
#: of all groups, which the six-parameter profiles share).
MATRIX = "matrix"
#: The entries of C above its diagonal.
_OFF_DIAGONAL = ((0, 1), (0, 2), (1, 2))


@dataclass(frozen=True)
class Coverage:
    """Per group, how many coefficients were checked and how many lay within ±U; and the
    units the solve refused (they carry no coefficient)."""

    checked: dict[str, int]
    inside: dict[str, int]
    refused: int
    mean_ratio: dict[str, float]

    def fraction(self, group: str | None = None) -> float:
        """Fraction within ±U of one group, or of all (``None``)."""
        groups = GROUPS if group is None else (group,)
        checked = sum(self.checked[g] for g in groups)
        return sum(self.inside[g] for g in groups) / checked if checked else float("nan")


def settings_of(profile: str) -> RunSettings:
    """The run settings a station uses under ``profile`` (its shipped plan, if any)."""
    return RunSettings(**(shipped_plan(profile) or {}))


def true_matrix(truth: SensorTruth) -> FloatArray:
    """The unit's nine-parameter matrix C (3, 3), g/count: the upper-triangular R of
    ``inv(counts_per_g) = Q·R`` with a positive diagonal (``|C(a − o)| = |g|`` for every
    reading, the fit's model)."""
    r = np.linalg.qr(np.linalg.inv(truth.counts_per_g))[1]
    return np.asarray(np.diag(np.sign(np.diag(r))) @ r, dtype=np.float64)


def true_sensitivity(truth: SensorTruth, model: Model) -> FloatArray:
    """The sensitivities as ``model`` defines them (module docstring)."""
    if model == "six":
        return truth.sensitivity_counts_per_g
    return np.asarray(1.0 / np.diag(true_matrix(truth)), dtype=np.float64)


def tilted(directions: FloatArray, tilt_deg: float, rng: np.random.Generator) -> FloatArray:
    """Each direction (N, 3) turned by up to ``tilt_deg`` about a random perpendicular axis."""
    if tilt_deg == 0.0:
        return directions
    out = np.empty_like(directions)
    for i, u in enumerate(directions):
        w = np.cross(u, rng.standard_normal(3))
        w /= np.linalg.norm(w)
        angle = np.radians(rng.uniform(0.0, tilt_deg))
        out[i] = Rotation.from_rotvec(angle * w).apply(u)
    return out


def simulate_coverage(
    profile: str,
    units: int,
    rng: np.random.Generator,
    tilt_deg: float = 0.0,
    pose_interval_s: float | None = None,
    knock_g: float = 0.0,
    knock_s: float = 1.0,
    cross_axis: float | None = None,
    gyro_turn_on_dps: float = 0.0,
    declare_turn_on: bool = True,
) -> Coverage:
    """Run ``units`` simulated units under ``profile``; count the truths within ±U.

    ``pose_interval_s``: ``None``, every pose at the reference temperature; else pose i is
    taken ``i·pose_interval_s`` after power-up, at the board's self-heated temperature
    (:class:`~station.simulator.sensor.Thermal`), from a unit whose temperature
    coefficients are drawn uniformly within the datasheet's bounds (those the budget
    assumes, :data:`~station.domain.sensors.sensor.OFFSET_TEMPCO_COUNTS_PER_C`,
    :data:`~station.domain.sensors.sensor.SENSITIVITY_TEMPCO_PER_C`); the truth is then the unit
    at the fitted poses' mean temperature, where the calibration holds.

    ``knock_g``: when not 0, one fitted pose of each unit, drawn at random, is knocked
    while it is taken: for ``knock_s`` seconds (at :data:`DEFAULT_RATE_HZ`, from a random
    sample) the sensor reads ``knock_g`` more along a random direction.

    ``cross_axis``: each unit's coupling drawn uniformly within ±cross_axis (not the
    KXM52's 2 %), and declared so to the budget.

    ``gyro_turn_on_dps``: the gyro bias moves from one power-on to the next by this
    (a standard deviation): each unit's session reads its bias plus a normal draw of it,
    and its truth is the bias over power-ons; ``declare_turn_on``: the budget is told
    (``repeatability_dps``)."""
    settings = settings_of(profile)
    names = (*settings.poses, settings.verification_pose)
    nominal = np.array([POSES[name].gravity_body for name in names])
    samples = settings.stillness.window_samples
    model: Model = settings.model
    checked = dict.fromkeys((*GROUPS, MATRIX), 0)
    inside = dict.fromkeys((*GROUPS, MATRIX), 0)
    ratio_sum = dict.fromkeys((*GROUPS, MATRIX), 0.0)
    refused = 0
    fit = len(settings.poses)
    temperatures = (
        np.full(len(names), REFERENCE_TEMPERATURE_C)
        if pose_interval_s is None
        else Thermal().at(pose_interval_s * np.arange(len(names), dtype=np.float64))
    )
    for _ in range(units):
        truth = SensorTruth.draw(rng)
        if cross_axis is not None:
            coupling = rng.uniform(-cross_axis, cross_axis, (3, 3)) * (1 - np.eye(3))
            truth = replace(truth, cross_axis=np.eye(3) + coupling)
        if pose_interval_s is not None:
            truth = replace(
                truth,
                offset_tempco_counts_per_c=rng.uniform(-1, 1, 3) * OFFSET_TEMPCO_COUNTS_PER_C,
                sensitivity_tempco_per_c=rng.uniform(-1, 1, 3) * SENSITIVITY_TEMPCO_PER_C,
            )
        directions = tilted(nominal, tilt_deg, rng)
        clean = np.array(
            [
                truth.at(t).still_counts(u[None, :])[0]
                for t, u in zip(temperatures, directions, strict=True)
            ]
        )  # (P, 3)
        truth = truth.at(float(np.mean(temperatures[:fit])))
        raw = clean[:, None, :] + rng.normal(0.0, truth.noise_counts, (len(names), samples, 3))
        if knock_g:
            length = min(samples, round(knock_s * DEFAULT_RATE_HZ))
            start = int(rng.integers(0, samples - length + 1))
            direction = rng.standard_normal(3)
            raw[int(rng.integers(0, fit)), start : start + length] += (
                knock_g * direction / np.linalg.norm(direction) * truth.sensitivity_counts_per_g
            )
        counts = np.clip(np.rint(raw), ADC_MIN, ADC_MAX)
        means, spread = counts.mean(axis=1), counts.std(axis=1, ddof=1)
        session_bias = truth.gyro_bias_dps
        if gyro_turn_on_dps:
            session_bias = session_bias + rng.normal(0.0, gyro_turn_on_dps, 3)
        rates = session_bias + rng.normal(0.0, truth.gyro_noise_dps, (len(names), samples, 3))
        rates = np.rint(rates / GYRO_DPS_PER_LSB) * GYRO_DPS_PER_LSB
        try:
            solution = solve(means[:fit], model)
        except CalibrationError:
            refused += 1
            continue
        budget = accelerometer_budget(
            solution,
            means[:fit],
            spread[:fit],
            np.full(fit, samples),
            verification=means[fit],
            verification_spread=spread[fit],
            verification_samples=samples,
            temperatures=None if pose_interval_s is None else temperatures[:fit],
            verification_temperature=None if pose_interval_s is None else temperatures[fit],
            cross_axis_bound=CROSS_AXIS_BOUND if cross_axis is None else cross_axis,
        )
        gyro_u = gyro_bias_uncertainty(
            rates.mean(axis=1),
            rates.std(axis=1, ddof=1),
            np.full(len(names), samples),
            repeatability_dps=gyro_turn_on_dps if declare_turn_on else 0.0,
        )
        cal = solution.calibration
        for group, estimate, true, u in (
            ("offset", cal.offset, truth.offset_counts, budget.offset),
            ("sensitivity", cal.sensitivity, true_sensitivity(truth, model), budget.sensitivity),
            ("gyro_bias", rates.mean(axis=(0, 1)), truth.gyro_bias_dps, gyro_u),
        ):
            error = np.abs(estimate - true)
            checked[group] += 3
            inside[group] += int(np.sum(error <= u))
            ratio_sum[group] += float(np.sum(error / u))
        if budget.matrix is not None:
            rows, columns = zip(*_OFF_DIAGONAL, strict=True)
            error = np.abs(cal.matrix - true_matrix(truth))[rows, columns]
            u = budget.matrix[rows, columns]
            checked[MATRIX] += 3
            inside[MATRIX] += int(np.sum(error <= u))
            ratio_sum[MATRIX] += float(np.sum(error / u))
    mean_ratio = {g: ratio_sum[g] / checked[g] if checked[g] else float("nan") for g in checked}
    return Coverage(checked, inside, refused, mean_ratio)


@dataclass(frozen=True)
class MatrixCoverage:
    """Of K's elements over the units: how many lay within ±U, per element (3, 3) of
    ``units`` units solved, and the mean |error|/U per element; and the units the solve
    refused."""

    units: int
    inside: FloatArray
    mean_ratio: FloatArray
    refused: int = 0

    def fraction(self) -> float:
        """Fraction of all elements within ±U."""
        return float(self.inside.sum() / (9 * self.units)) if self.units else float("nan")


def simulate_gyro_matrix_coverage(
    profile: str, units: int, rng: np.random.Generator
) -> MatrixCoverage:
    """Run ``units`` simulated whole units' streams over ``profile``'s poses (module
    docstring); count K's elements whose truth lies within ±U."""
    settings = settings_of(profile)
    names = (*settings.poses, settings.verification_pose)
    directions = np.array([POSES[name].gravity_body for name in names])
    inside = np.zeros((3, 3))
    ratio = np.zeros((3, 3))
    refused = 0
    for _ in range(units):
        imu = random_imu(rng)
        stream = recorded_stream(rng, imu, pose_orientations(rng, directions))
        try:
            result = calibrate_stream(stream, settings.model)
        except CalibrationError:
            # The six-parameter model leaves the coupling out, and on poses the moves
            # have tilted off the axes a seventh pose can be inconsistent with the six.
            refused += 1
            continue
        u = result.uncertainty.gyro_matrix
        if result.gyro is None or u is None:
            refused += 1  # the moves did not determine K
            continue
        error = np.abs(result.gyro.scale_matrix - k_in_calibrated_frame(imu, settings.model))
        inside += error <= u
        ratio += error / u
    solved = units - refused
    return MatrixCoverage(solved, inside, ratio / max(solved, 1), refused)
