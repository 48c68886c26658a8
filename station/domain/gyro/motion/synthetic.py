"""Synthetic calibration streams with known truth, for tests and benchmarks.

A unit is an accelerometer (:class:`station.domain.calibration.synthetic.TrueUnit`, counts
``a = o + S·f`` for specific force f in g, body frame) and a gyro triad reading
``m = b + K·ω + n`` (deg/s, ω the body rate). The operator holds it still in a
sequence of orientations (body-to-world rotations; at rest the specific force is
``Rᵀ·ẑ``, 1 g up) and turns it from each to the next in ``move_s`` seconds along a
minimum-jerk profile ``s(τ) = 10τ³ − 15τ⁴ + 6τ⁵`` of the relative rotation vector
(the hand's usual profile, as the virtual putter's motion), plus a wobble about a
random axis whose rate ``A·(2π/T)·sin 2πτ`` is zero at both ends. The true
orientation is integrated at eight sub-steps per sample, so the next pose is where the
turn actually ended. During a move the accelerometer reads the nominal path's gravity
(only the stills are fitted).

In the calibrated accelerometer's frame the true K differs from the body-frame K:
the nine-parameter calibration is ``C = Q·S⁻¹`` with C upper triangular and Q a
rotation (the QR factors of S⁻¹), and ω_cal = Q·ω, so ``K_cal = K·Qᵀ``
(:meth:`SyntheticImu.k_in_calibrated_frame`).
"""

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from station.domain.arrays import FloatArray
from station.domain.calibration import Model
from station.domain.calibration.synthetic import TrueUnit, random_unit
from station.domain.gyro.motion.integrate import ordered_product
from station.domain.gyro.motion.stream import RecordedStream

#: Sub-steps per sample when integrating the true orientation.
TRUTH_SUBSTEPS = 8
_UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True, eq=False)
class SyntheticImu:
    """A unit with known accelerometer, gyro matrix (body frame) and gyro bias."""

    accel: TrueUnit
    k: FloatArray
    bias_dps: FloatArray

    def k_in_calibrated_frame(self, model: Model) -> FloatArray:
        """K as ``model``'s exact calibration sees it (module docstring).

        The six-parameter calibration keeps the body axes (its matrix is diagonal).
        """
        if model == "six":
            return self.k
        q_t, r = np.linalg.qr(np.linalg.inv(self.accel.scale))
        signs = np.sign(np.diag(r))
        return np.asarray(self.k @ (q_t * signs), dtype=np.float64)


@dataclass(frozen=True)
class StreamPlan:
    """How a synthetic stream is recorded: rate, durations, motion and noise."""

    rate_hz: float = 500.0
    still_s: float = 2.0
    move_s: float = 1.5
    wobble_deg: float = 5.0
    accel_noise_counts: float = 1.0
    gyro_noise_dps: float = 0.08


def random_imu(
    rng: np.random.Generator,
    *,
    cross_axis: float = 0.02,
    scale: float = 0.01,
    misalignment: float = 0.005,
    bias_dps: float = 0.3,
) -> SyntheticImu:
    """A unit with uniform errors: scale ±``scale``, off-diagonal ±``misalignment``."""
    k = np.eye(3) + np.diag(rng.uniform(-scale, scale, 3))
    off = rng.uniform(-misalignment, misalignment, (3, 3))
    np.fill_diagonal(off, 0.0)
    return SyntheticImu(
        accel=random_unit(rng, cross_axis=cross_axis),
        k=k + off,
        bias_dps=rng.uniform(-bias_dps, bias_dps, 3),
    )


def pose_orientations(rng: np.random.Generator, directions: FloatArray) -> Rotation:
    """Body-to-world rotations whose still accelerometer reads along ``directions``.

    Each is turned by a random angle about the vertical, so that the moves between
    them turn about varied axes.
    """
    units = directions / np.linalg.norm(directions, axis=1, keepdims=True)
    tilts = [Rotation.align_vectors(_UP[None, :], u[None, :])[0] for u in units]
    yaws = Rotation.from_rotvec(np.outer(rng.uniform(-np.pi, np.pi, len(units)), _UP))
    return yaws * Rotation.concatenate(tilts)


def _still_samples(
    imu: SyntheticImu, orientation: Rotation, n: int, plan: StreamPlan, rng: np.random.Generator
) -> tuple[FloatArray, FloatArray]:
    force = orientation.inv().apply(_UP)
    accel = np.tile(imu.accel.counts(force[None, :]), (n, 1))
    gyro = np.tile(imu.bias_dps, (n, 1))
    return (
        accel + rng.normal(0.0, plan.accel_noise_counts, accel.shape),
        gyro + rng.normal(0.0, plan.gyro_noise_dps, gyro.shape),
    )


def _move_samples(
    imu: SyntheticImu,
    start: Rotation,
    target: Rotation,
    n: int,
    plan: StreamPlan,
    rng: np.random.Generator,
) -> tuple[FloatArray, FloatArray, Rotation]:
    """Samples strictly inside a move of n + 1 steps, and the orientation it ends in."""
    duration = (n + 1) / plan.rate_hz
    phi = (start.inv() * target).as_rotvec()
    axis = rng.standard_normal(3)
    wobble = np.radians(plan.wobble_deg) * axis / np.linalg.norm(axis)

    def rate(tau: FloatArray) -> FloatArray:
        s_dot = 30 * tau**2 - 60 * tau**3 + 30 * tau**4
        return np.asarray(
            (np.outer(s_dot, phi) + np.outer(2 * np.pi * np.sin(2 * np.pi * tau), wobble))
            / duration,
            dtype=np.float64,
        )

    substeps = (n + 1) * TRUTH_SUBSTEPS
    mid = (np.arange(substeps) + 0.5) / substeps
    end = start * ordered_product(Rotation.from_rotvec(rate(mid) * (duration / substeps)))
    tau = np.arange(1, n + 1) / (n + 1)
    s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
    nominal = start * Rotation.from_rotvec(np.outer(s, phi))
    accel = imu.accel.counts(nominal.inv().apply(_UP))
    gyro = imu.bias_dps + np.degrees(rate(tau)) @ imu.k.T
    return (
        accel + rng.normal(0.0, plan.accel_noise_counts, accel.shape),
        gyro + rng.normal(0.0, plan.gyro_noise_dps, gyro.shape),
        end,
    )


def synthetic_stream(
    rng: np.random.Generator,
    imu: SyntheticImu,
    orientations: Rotation,
    plan: StreamPlan = StreamPlan(),
) -> RecordedStream:
    """The unit's raw stream over stills at ``orientations`` joined by moves."""
    still_n = round(plan.still_s * plan.rate_hz)
    move_n = round(plan.move_s * plan.rate_hz) - 1
    current = orientations[0]
    accel, gyro = _still_samples(imu, current, still_n, plan, rng)
    accel_parts, gyro_parts = [accel], [gyro]
    for i in range(1, len(orientations)):
        accel, gyro, current = _move_samples(imu, current, orientations[i], move_n, plan, rng)
        accel_parts.append(accel)
        gyro_parts.append(gyro)
        accel, gyro = _still_samples(imu, current, still_n, plan, rng)
        accel_parts.append(accel)
        gyro_parts.append(gyro)
    accel_all = np.concatenate(accel_parts)
    return RecordedStream(
        t=np.arange(len(accel_all)) / plan.rate_hz,
        accel_counts=accel_all,
        gyro_dps=np.concatenate(gyro_parts),
    )
