"""Motion model of the virtual putter: an operator moving it between poses.

A move from orientation ``R₀`` to ``R₁`` over ``T`` seconds follows a minimum-jerk
profile ``s(τ) = 10τ³ − 15τ⁴ + 6τ⁵`` (τ = t/T) along the shortest rotation
``φ = log(R₀⁻¹ R₁)``::

    R(t) = R₀ · exp(s(τ) φ)            ω_body(t) = ṡ(τ) φ

while the hand lifts the head by ``h`` (``z = h sin²(πτ)``) and carries it ``d``
sideways (minimum jerk too): the handling accelerations the accelerometer cannot tell
from gravity. Once put down, the unit settles with a tremor that decays with time
constant ``τ_s``: a small rocking ``θ(t) = θ₀ e^{−t/τ_s} sin(2π f t)`` about a random
body axis, and a linear shake of amplitude ``a₀`` along a random direction. A unit
that never settles keeps its initial tremor.
"""

from dataclasses import dataclass
from typing import Final

import numpy as np
from scipy.spatial.transform import Rotation

from station.domain.arrays import FloatArray

STANDARD_GRAVITY: Final = 9.80665  # m/s²
UP: Final = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Handling:
    """How the operator moves and puts down the unit."""

    lift_m: float = 0.10
    carry_m: float = 0.25
    tremor_rock_deg: float = 0.1
    tremor_rock_hz: float = 9.0
    tremor_shake_g: float = 0.02
    tremor_shake_hz: float = 12.0
    settle_time_constant_s: float = 0.25


@dataclass(frozen=True)
class Kinematics:
    """What the sensors see at N instants: specific force (g) and rates (deg/s), body axes."""

    force_g: FloatArray
    rate_dps: FloatArray


def _unit(v: FloatArray) -> FloatArray:
    return np.asarray(v / np.linalg.norm(v), dtype=np.float64)


class MotionModel:
    """Orientation of the unit in simulated time, driven by :meth:`move_to`."""

    def __init__(
        self, start: Rotation, rng: np.random.Generator, handling: Handling | None = None
    ) -> None:
        self.handling = handling or Handling()
        self.never_settles = False
        self._rng = rng
        self._from = start
        self._to = start
        self._t0 = -np.inf
        self._duration = 1.0
        self._carry_dir = np.array([1.0, 0.0, 0.0])
        self._rock_axis = np.array([1.0, 0.0, 0.0])
        self._shake_dir = np.array([0.0, 0.0, 1.0])
        self._tremor = False

    @property
    def target(self) -> Rotation:
        """Where the current (or last) move goes."""
        return self._to

    def settled_at(self) -> float:
        """Simulated time from which the tremor is below 1 % of its start."""
        return self._t0 + self._duration + 4.6 * self.handling.settle_time_constant_s

    def move_to(self, target: Rotation, now: float, duration: float = 1.5) -> None:
        """Start moving to ``target`` at simulated time ``now``, over ``duration`` s."""
        if duration <= 0:
            raise ValueError(f"a move takes a positive time, got {duration}")
        self._from = self._orientation(np.array([now]))[0]
        self._to = target
        self._t0 = now
        self._duration = duration
        rng = self._rng
        heading = rng.uniform(0, 2 * np.pi)
        self._carry_dir = np.array([np.cos(heading), np.sin(heading), 0.0])
        self._rock_axis = _unit(rng.normal(size=3))
        self._shake_dir = _unit(rng.normal(size=3))
        self._tremor = True

    def _phase(self, t: FloatArray) -> tuple[FloatArray, FloatArray]:
        tau = np.clip((t - self._t0) / self._duration, 0.0, 1.0)
        s = tau**3 * (10 - 15 * tau + 6 * tau**2)
        s_dot = 30 * tau**2 * (1 - tau) ** 2 / self._duration
        return s, s_dot

    def _orientation(self, t: FloatArray) -> Rotation:
        s, _ = self._phase(t)
        phi = (self._from.inv() * self._to).as_rotvec()
        return self._from * Rotation.from_rotvec(s[:, None] * phi)

    def evaluate(self, t: FloatArray) -> Kinematics:
        """Specific force and body rates at simulated times ``t`` (1-D, seconds)."""
        h = self.handling
        T = self._duration
        s, s_dot = self._phase(t)
        phi = (self._from.inv() * self._to).as_rotvec()
        rate = s_dot[:, None] * phi
        tau = np.clip((t - self._t0) / T, 0.0, 1.0)
        moving = ((t > self._t0) & (t < self._t0 + T))[:, None]
        lift = h.lift_m * 2 * np.pi**2 / T**2 * np.cos(2 * np.pi * tau)
        carry = h.carry_m * (60 * tau - 180 * tau**2 + 120 * tau**3) / T**2
        accel_world = (
            np.where(moving, lift[:, None] * UP + carry[:, None] * self._carry_dir, 0.0)
            / STANDARD_GRAVITY
        )
        orientation = self._from * Rotation.from_rotvec(s[:, None] * phi)
        if self._tremor:
            after = np.maximum(t - (self._t0 + T), 0.0)
            envelope = (
                np.ones_like(after)
                if self.never_settles
                else np.exp(-after / h.settle_time_constant_s)
            )
            envelope = np.where(t > self._t0 + T, envelope, 0.0)
            w = 2 * np.pi * h.tremor_rock_hz
            theta0 = np.radians(h.tremor_rock_deg)
            theta = theta0 * envelope * np.sin(w * after)
            decay = 0.0 if self.never_settles else 1 / h.settle_time_constant_s
            theta_dot = theta0 * envelope * (w * np.cos(w * after) - decay * np.sin(w * after))
            orientation = orientation * Rotation.from_rotvec(theta[:, None] * self._rock_axis)
            rate = rate + theta_dot[:, None] * self._rock_axis
            shake = h.tremor_shake_g * envelope * np.sin(2 * np.pi * h.tremor_shake_hz * after)
            accel_world = accel_world + shake[:, None] * self._shake_dir
        force = orientation.inv().apply(UP + accel_world)
        return Kinematics(
            force_g=np.atleast_2d(np.asarray(force, dtype=np.float64)),
            rate_dps=np.degrees(rate),
        )
