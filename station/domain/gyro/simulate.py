"""Simulated rate-table and centrifuge logs of the g-sensitivity test, from a known truth.

The test of [Park2014]_ section 2.3: a centrifuge with a 3 m arm spins the unit so
that the radial specific force a = ω²r steps through 3, 6, …, 30 g; the spin axis is
vertical, so gravity (1 g) lies along it. Mounting the unit with a body axis i along
the spin axis and a body axis j along the arm, the unit sees::

    ω_i = ±Ω,   a_i = ±1 g (spin axis up or down),   a_j = ±Ω²r/g0 (toward the hub or away)

The default plan runs every input axis i with the arm along both other axes, each
both ways (12 mounts, so −30 g … +30 g along every axis), both spin directions, plus
rate-table steps about every axis with gravity up and down along it (and the still
poses at rate zero). Noise is white on every row: gyro (deg/s) and accelerometer (g).
"""

from dataclasses import dataclass, field

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.constants import DEFAULT_SENSE_AXES, PAPER_PPM_PER_G
from station.domain.gyro.log import GyroLog
from station.domain.gyro.model import PPM, GyroErrorModel

G0 = 9.80665  # m/s², standard gravity

DEFAULT_BIAS_DPS = (0.02, -0.015, 0.01)
DEFAULT_SCALE = (
    (1.0 + 700e-6, 1.2e-3, -0.8e-3),
    (-0.5e-3, 1.0 - 400e-6, 0.9e-3),
    (1.1e-3, -0.6e-3, 1.0 + 300e-6),
)


def paper_truth(
    ppm_per_g: tuple[float, float, float] = PAPER_PPM_PER_G,
    sense_axes: tuple[int, int, int] = DEFAULT_SENSE_AXES,
    bias_form_dps_per_g: tuple[float, float, float] = (0.0, 0.0, 0.0),
    bias_dps: tuple[float, float, float] = DEFAULT_BIAS_DPS,
) -> GyroErrorModel:
    """A truth with one g-sensitivity term per gyro on its sense axis.

    ``ppm_per_g`` goes to ``N[i, sense_axes[i]]`` (scale-factor form), and
    ``bias_form_dps_per_g`` to ``B[i, sense_axes[i]]`` (bias form).
    """
    n_g = np.zeros((3, 3))
    bias_g = np.zeros((3, 3))
    for i, j in enumerate(sense_axes):
        n_g[i, j] = ppm_per_g[i] / PPM
        bias_g[i, j] = bias_form_dps_per_g[i]
    return GyroErrorModel(np.array(bias_dps), np.array(DEFAULT_SCALE), bias_g, n_g)


@dataclass(frozen=True)
class Mount:
    """Unit on the arm: body ``input_axis`` along the spin axis, ``radial_axis`` along the arm.

    ``up`` = +1 when the input axis points up (gravity reads +1 g on it); ``inward`` = +1
    when the radial axis points toward the hub (the centrifugal specific force reads
    positive on it).
    """

    input_axis: int
    up: int
    radial_axis: int
    inward: int


def default_mounts() -> tuple[Mount, ...]:
    """Twelve mounts: every input axis, the arm along both other axes, both ways."""
    return tuple(
        Mount(i, inward if n == 0 else -inward, j, inward)
        for i in range(3)
        for n, j in enumerate(j for j in range(3) if j != i)
        for inward in (1, -1)
    )


@dataclass(frozen=True)
class CentrifugePlan:
    """The centrifuge and rate-table schedule.

    ``rate_table`` adds, for every axis with gravity up and down along it, the still
    pose and the ``table_rates_dps`` steps both ways.
    """

    arm_m: float = 3.0
    g_max: float = 30.0
    g_step: float = 3.0
    mounts: tuple[Mount, ...] = field(default_factory=default_mounts)
    both_directions: bool = True
    rate_table: bool = True
    table_rates_dps: tuple[float, ...] = (50.0, 150.0, 300.0, 600.0)
    dwell_s: float = 10.0

    def centrifuge_levels_g(self) -> FloatArray:
        """Radial acceleration levels, g: g_step, 2·g_step, …, g_max."""
        count = round(self.g_max / self.g_step)
        return self.g_step * np.arange(1, count + 1, dtype=np.float64)

    def spin_dps(self, level_g: FloatArray) -> FloatArray:
        """Spin rate (deg/s) that gives the radial acceleration ``level_g`` on the arm."""
        return np.degrees(np.sqrt(level_g * G0 / self.arm_m))


@dataclass(frozen=True)
class Noise:
    """White noise per row: gyro (deg/s) and accelerometer (g)."""

    gyro_dps: float = 0.01
    acc_g: float = 0.001


def dwells(plan: CentrifugePlan) -> tuple[FloatArray, FloatArray]:
    """True rate (deg/s) and specific force (g) of every dwell of ``plan``, N-by-3 each."""
    rates: list[FloatArray] = []
    accs: list[FloatArray] = []
    levels = plan.centrifuge_levels_g()
    spins = plan.spin_dps(levels)
    directions = (1.0, -1.0) if plan.both_directions else (1.0,)
    for m in plan.mounts:
        for direction in directions:
            rate = np.zeros((levels.size, 3))
            acc = np.zeros((levels.size, 3))
            rate[:, m.input_axis] = m.up * direction * spins
            acc[:, m.input_axis] = m.up
            acc[:, m.radial_axis] = m.inward * levels
            rates.append(rate)
            accs.append(acc)
    table = np.concatenate([[0.0], plan.table_rates_dps, -np.asarray(plan.table_rates_dps)])
    for i in range(3 if plan.rate_table else 0):
        for up in (1.0, -1.0):
            rate = np.zeros((table.size, 3))
            acc = np.zeros((table.size, 3))
            rate[:, i] = table
            acc[:, i] = up
            rates.append(rate)
            accs.append(acc)
    return np.concatenate(rates), np.concatenate(accs)


def simulate_log(
    truth: GyroErrorModel,
    plan: CentrifugePlan | None = None,
    noise: Noise | None = None,
    samples_per_dwell: int = 1,
    seed: int | None = None,
) -> tuple[GyroLog, list[str] | None]:
    """Simulate the test; returns the log and, when ``samples_per_dwell`` > 1, segment labels."""
    plan = plan or CentrifugePlan()
    noise = noise or Noise()
    if samples_per_dwell < 1:
        raise ValueError("samples_per_dwell must be at least 1")
    rng = np.random.default_rng(seed)
    rate, acc = dwells(plan)
    count = rate.shape[0]
    rate = np.repeat(rate, samples_per_dwell, axis=0)
    acc = np.repeat(acc, samples_per_dwell, axis=0)
    dwell_index = np.repeat(np.arange(count), samples_per_dwell)
    sample_index = np.tile(np.arange(samples_per_dwell), count)
    t = plan.dwell_s * (dwell_index + sample_index / samples_per_dwell)
    gyro = truth.predict(rate, acc) + rng.normal(0.0, noise.gyro_dps, rate.shape)
    acc_measured = acc + rng.normal(0.0, noise.acc_g, acc.shape)
    log = GyroLog(t=t, rate=rate, acc=acc_measured, gyro=gyro)
    segments = [f"d{k}" for k in dwell_index] if samples_per_dwell > 1 else None
    return log, segments
