"""Recordings of virtual units with known truth, without the wire: still-pose means and
raw calibration streams, for the accuracy tests and the benchmarks.

The units are the simulator's own (:class:`station.simulator.sensor.SensorTruth`): at rest
the accelerometer reads ``a = o + S·f`` (counts; f the specific force in g, body frame;
``S = diag(s)·C``, :meth:`~station.simulator.sensor.SensorTruth.still_counts`) and the
gyros ``m = b + K·ω`` (deg/s, ω the body rate; :attr:`~SensorTruth.gyro_matrix`). The exact
calibration of such a unit is ``S⁻¹``; its six-parameter part is ``diag(1/s)`` only when
the cross-axis coupling is zero.

A stream (:func:`recorded_stream`): the operator holds the unit still in a sequence of
orientations (body-to-world rotations; at rest the specific force is ``Rᵀ·ẑ``, 1 g up)
and turns it from each to the next in ``move_s`` seconds along a minimum-jerk profile
``s(τ) = 10τ³ − 15τ⁴ + 6τ⁵`` of the relative rotation vector (the hand's usual profile,
as the virtual putter's motion, :mod:`station.simulator.motion`), plus a wobble about a
random axis whose rate ``A·(2π/T)·sin 2πτ`` is zero at both ends. The true orientation is
integrated at eight sub-steps per sample, so the next pose is where the turn actually
ended. During a move the accelerometer reads the nominal path's gravity (only the stills
are fitted).

In the calibrated accelerometer's frame the true K differs from the body-frame K: the
nine-parameter calibration is ``C = Q·S⁻¹`` with C upper triangular and Q a rotation (the
QR factors of S⁻¹), and ω_cal = Q·ω, so ``K_cal = K·Qᵀ`` (:func:`k_in_calibrated_frame`).
"""

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from station.domain.arrays import FloatArray
from station.domain.calibration import Model
from station.domain.gyro.motion import RecordedStream
from station.domain.gyro.motion.integrate import ordered_product
from station.simulator.sensor import SensorTruth

#: Sub-steps per sample when integrating the true orientation.
TRUTH_SUBSTEPS = 8
_UP = np.array([0.0, 0.0, 1.0])


def random_directions(rng: np.random.Generator, n: int) -> FloatArray:
    """n unit vectors drawn uniformly on the sphere, (n, 3)."""
    v = rng.standard_normal((n, 3))
    return np.asarray(v / np.linalg.norm(v, axis=1, keepdims=True), dtype=np.float64)


def spread_directions(n: int) -> FloatArray:
    """n unit vectors spread evenly over the sphere (Fibonacci lattice), (n, 3)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = np.pi * (1.0 + np.sqrt(5.0)) * i
    r = np.sqrt(1.0 - z * z)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), z])


def six_directions(rng: np.random.Generator | None = None, tilt_deg: float = 0.0) -> FloatArray:
    """The six ±1 g poses (+x, −x, +y, −y, +z, −z), each tilted by ``tilt_deg``.

    The tilt is applied about a random axis perpendicular to each direction (a jig
    misplaced by that angle); ``rng`` may be None only when ``tilt_deg`` is 0.
    """
    base = np.array(
        [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64
    )
    if tilt_deg == 0.0:
        return base
    if rng is None:
        raise ValueError("a tilt needs a random generator")
    theta = np.radians(tilt_deg)
    out = np.empty_like(base)
    for i, u in enumerate(base):
        w = rng.standard_normal(3)
        w -= (w @ u) * u
        w /= np.linalg.norm(w)
        out[i] = np.cos(theta) * u + np.sin(theta) * w
    return out


def pose_means(
    truth: SensorTruth, directions: FloatArray, noise_counts: float, rng: np.random.Generator
) -> FloatArray:
    """Mean counts of still poses with gravity along ``directions`` (N, 3).

    ``noise_counts`` is the standard deviation of each pose mean per axis (the sample
    noise divided by √(samples per pose)).
    """
    clean = truth.still_counts(directions)
    return np.asarray(clean + rng.normal(0.0, noise_counts, clean.shape), dtype=np.float64)


@dataclass(frozen=True)
class StreamPlan:
    """How a synthetic stream is recorded: rate, durations, motion and noise."""

    rate_hz: float = 500.0
    still_s: float = 2.0
    move_s: float = 1.5
    wobble_deg: float = 5.0
    #: A whole turn's axis off the vertical (degrees, about a random horizontal axis): a
    #: hand's Ferraris turn is not exactly about the vertical.
    turn_tilt_deg: float = 0.0
    accel_noise_counts: float = 1.0
    gyro_noise_dps: float = 0.08


def random_imu(
    rng: np.random.Generator,
    *,
    cross_axis: float = 0.02,
    scale: float = 0.01,
    misalignment: float = 0.005,
    bias_dps: float = 0.3,
) -> SensorTruth:
    """A unit with uniform errors: accelerometer as
    :meth:`~station.simulator.sensor.SensorTruth.draw_accelerometer`, gyro scale
    ±``scale``, off-diagonal ±``misalignment``, bias ±``bias_dps``."""
    k = np.eye(3) + np.diag(rng.uniform(-scale, scale, 3))
    off = rng.uniform(-misalignment, misalignment, (3, 3))
    np.fill_diagonal(off, 0.0)
    accel = SensorTruth.draw_accelerometer(rng, cross_axis=cross_axis)
    return SensorTruth.accelerometer(
        accel.offset_counts,
        accel.counts_per_g,
        gyro_matrix=k + off,
        gyro_bias_dps=rng.uniform(-bias_dps, bias_dps, 3),
    )


def k_in_calibrated_frame(truth: SensorTruth, model: Model) -> FloatArray:
    """K as ``model``'s exact calibration sees it (module docstring).

    The six-parameter calibration keeps the body axes (its matrix is diagonal).
    """
    if model == "six":
        return truth.gyro_matrix
    q_t, r = np.linalg.qr(np.linalg.inv(truth.counts_per_g))
    signs = np.sign(np.diag(r))
    return np.asarray(truth.gyro_matrix @ (q_t * signs), dtype=np.float64)


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
    truth: SensorTruth, orientation: Rotation, n: int, plan: StreamPlan, rng: np.random.Generator
) -> tuple[FloatArray, FloatArray]:
    force = orientation.inv().apply(_UP)
    accel = np.tile(truth.still_counts(force[None, :]), (n, 1))
    gyro = np.tile(truth.gyro_bias_dps, (n, 1))
    return (
        accel + rng.normal(0.0, plan.accel_noise_counts, accel.shape),
        gyro + rng.normal(0.0, plan.gyro_noise_dps, gyro.shape),
    )


def _move_samples(
    truth: SensorTruth,
    start: Rotation,
    phi: FloatArray,
    n: int,
    plan: StreamPlan,
    rng: np.random.Generator,
) -> tuple[FloatArray, FloatArray, Rotation]:
    """Samples strictly inside a move of n + 1 steps turning by the rotation vector
    ``phi`` (body frame, radians), and the orientation it ends in."""
    duration = (n + 1) / plan.rate_hz
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
    accel = truth.still_counts(nominal.inv().apply(_UP))
    gyro = truth.gyro_bias_dps + np.degrees(rate(tau)) @ truth.gyro_matrix.T
    return (
        accel + rng.normal(0.0, plan.accel_noise_counts, accel.shape),
        gyro + rng.normal(0.0, plan.gyro_noise_dps, gyro.shape),
        end,
    )


def recorded_stream(
    rng: np.random.Generator,
    truth: SensorTruth,
    orientations: Rotation,
    plan: StreamPlan = StreamPlan(),
    turns: Mapping[int, float] | None = None,
) -> RecordedStream:
    """The unit's raw stream over stills at ``orientations`` joined by moves.

    ``turns``: after the still at orientation ``i``, a turn of ``turns[i]`` degrees about
    the vertical (``plan.turn_tilt_deg`` off it), then a still again (Ferraris' whole
    turns: 360° about any axis brings the unit back where it was).
    """
    still_n = round(plan.still_s * plan.rate_hz)
    move_n = round(plan.move_s * plan.rate_hz) - 1
    current = orientations[0]
    accel, gyro = _still_samples(truth, current, still_n, plan, rng)
    accel_parts, gyro_parts = [accel], [gyro]
    moves: list[tuple[int, float | None]] = []
    for i in range(len(orientations)):
        if turns is not None and i in turns:
            moves.append((i, turns[i]))
        if i + 1 < len(orientations):
            moves.append((i + 1, None))
    for i, turn_deg in moves:
        if turn_deg is None:
            phi = (current.inv() * orientations[i]).as_rotvec()
        else:
            axis = _UP
            if plan.turn_tilt_deg:
                horizontal = np.cross(_UP, rng.standard_normal(3))
                tilt = np.radians(plan.turn_tilt_deg) * horizontal / np.linalg.norm(horizontal)
                axis = Rotation.from_rotvec(tilt).apply(_UP)
            phi = np.radians(turn_deg) * current.inv().apply(axis)
        accel, gyro, current = _move_samples(truth, current, phi, move_n, plan, rng)
        accel_parts.append(accel)
        gyro_parts.append(gyro)
        accel, gyro = _still_samples(truth, current, still_n, plan, rng)
        accel_parts.append(accel)
        gyro_parts.append(gyro)
    accel_all = np.concatenate(accel_parts)
    return RecordedStream(
        t=np.arange(len(accel_all)) / plan.rate_hz,
        accel_counts=accel_all,
        gyro_dps=np.concatenate(gyro_parts),
    )
