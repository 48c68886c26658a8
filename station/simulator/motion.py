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
from functools import cached_property
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


@dataclass(frozen=True)
class _Move:
    """One move: from ``start`` to ``target`` over ``duration`` s from ``t0``, with the
    carry's heading and the tremor's directions drawn for it (none before the first)."""

    start: Rotation
    target: Rotation
    t0: float
    duration: float
    carry_dir: FloatArray
    rock_axis: FloatArray
    shake_dir: FloatArray
    tremor: bool

    def phase(self, t: FloatArray) -> tuple[FloatArray, FloatArray]:
        tau = np.clip((t - self.t0) / self.duration, 0.0, 1.0)
        s = tau**3 * (10 - 15 * tau + 6 * tau**2)
        s_dot = 30 * tau**2 * (1 - tau) ** 2 / self.duration
        return s, s_dot

    @cached_property
    def turn(self) -> FloatArray:
        """φ = log(R₀⁻¹ R₁), the rotation vector of the whole move (body axes)."""
        return np.asarray((self.start.inv() * self.target).as_rotvec(), dtype=np.float64)

    def along(self, s: FloatArray) -> Rotation:
        """R₀ · exp(s φ): the orientation a fraction ``s`` of the way."""
        return self.start * Rotation.from_rotvec(s[:, None] * self.turn)

    def orientation(self, t: FloatArray) -> Rotation:
        return self.along(self.phase(t)[0])

    def settled_at(self, handling: Handling) -> float:
        return self.t0 + self.duration + 4.6 * handling.settle_time_constant_s

    def evaluate(self, t: FloatArray, h: Handling, never_settles: bool) -> Kinematics:
        T = self.duration
        s, s_dot = self.phase(t)
        rate = s_dot[:, None] * self.turn
        tau = np.clip((t - self.t0) / T, 0.0, 1.0)
        moving = ((t > self.t0) & (t < self.t0 + T))[:, None]
        lift = h.lift_m * 2 * np.pi**2 / T**2 * np.cos(2 * np.pi * tau)
        carry = h.carry_m * (60 * tau - 180 * tau**2 + 120 * tau**3) / T**2
        accel_world = (
            np.where(moving, lift[:, None] * UP + carry[:, None] * self.carry_dir, 0.0)
            / STANDARD_GRAVITY
        )
        orientation = self.along(s)
        if self.tremor:
            after = np.maximum(t - (self.t0 + T), 0.0)
            envelope = (
                np.ones_like(after) if never_settles else np.exp(-after / h.settle_time_constant_s)
            )
            envelope = np.where(t > self.t0 + T, envelope, 0.0)
            w = 2 * np.pi * h.tremor_rock_hz
            theta0 = np.radians(h.tremor_rock_deg)
            theta = theta0 * envelope * np.sin(w * after)
            decay = 0.0 if never_settles else 1 / h.settle_time_constant_s
            theta_dot = theta0 * envelope * (w * np.cos(w * after) - decay * np.sin(w * after))
            orientation = orientation * Rotation.from_rotvec(theta[:, None] * self.rock_axis)
            rate = rate + theta_dot[:, None] * self.rock_axis
            shake = h.tremor_shake_g * envelope * np.sin(2 * np.pi * h.tremor_shake_hz * after)
            accel_world = accel_world + shake[:, None] * self.shake_dir
        force = orientation.inv().apply(UP + accel_world)
        return Kinematics(
            force_g=np.atleast_2d(np.asarray(force, dtype=np.float64)),
            rate_dps=np.degrees(rate),
        )


class MotionModel:
    """Orientation of the unit in simulated time, driven by :meth:`move_to`.

    Moves may be queued: a move starting later than another one leaves that one to run
    until it starts (an operator who puts the unit down, then picks it up again at a
    time the test chooses in simulated time, whatever the wall clock does meanwhile).
    A move starting no later than a queued one replaces it.
    """

    def __init__(
        self, start: Rotation, rng: np.random.Generator, handling: Handling | None = None
    ) -> None:
        self.handling = handling or Handling()
        self.never_settles = False
        self._rng = rng
        still = _Move(
            start=start,
            target=start,
            t0=-np.inf,
            duration=1.0,
            carry_dir=np.array([1.0, 0.0, 0.0]),
            rock_axis=np.array([1.0, 0.0, 0.0]),
            shake_dir=np.array([0.0, 0.0, 1.0]),
            tremor=False,
        )
        self._moves = [still]
        self._evaluated_to = -np.inf

    @property
    def target(self) -> Rotation:
        """Where the last move goes."""
        return self._moves[-1].target

    def settled_at(self) -> float:
        """Simulated time from which the last move's tremor is below 1 % of its start."""
        return self._moves[-1].settled_at(self.handling)

    def move_to(self, target: Rotation, now: float, duration: float = 1.5) -> None:
        """Start moving to ``target`` at simulated time ``now``, over ``duration`` s."""
        if duration <= 0:
            raise ValueError(f"a move takes a positive time, got {duration}")
        kept = [move for move in self._moves if move.t0 < now]
        # Before every move kept (a past already forgotten): from where the first starts.
        base = kept[-1] if kept else self._moves[0]
        # The moves before the one the next sample to draw falls in are done with.
        while len(kept) > 1 and kept[1].t0 <= self._evaluated_to:
            kept.pop(0)
        rng = self._rng
        heading = rng.uniform(0, 2 * np.pi)
        kept.append(
            _Move(
                start=base.orientation(np.array([now]))[0],
                target=target,
                t0=now,
                duration=duration,
                carry_dir=np.array([np.cos(heading), np.sin(heading), 0.0]),
                rock_axis=_unit(rng.normal(size=3)),
                shake_dir=_unit(rng.normal(size=3)),
                tremor=True,
            )
        )
        self._moves = kept

    def evaluate(self, t: FloatArray) -> Kinematics:
        """Specific force and body rates at simulated times ``t`` (1-D, seconds)."""
        if len(t):
            self._evaluated_to = max(self._evaluated_to, float(t.max()))
        starts = np.array([move.t0 for move in self._moves])
        # Times before the first move kept (a trace of the past) take that move.
        which = np.maximum(np.searchsorted(starts, t, side="right") - 1, 0)
        force = np.empty((len(t), 3))
        rate = np.empty((len(t), 3))
        for index in np.unique(which):
            at = which == index
            kin = self._moves[index].evaluate(t[at], self.handling, self.never_settles)
            force[at] = kin.force_g
            rate[at] = kin.rate_dps
        return Kinematics(force_g=force, rate_dps=rate)
