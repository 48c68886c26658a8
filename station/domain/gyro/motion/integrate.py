"""Integrating body rates on SO(3): the rotation a move turned the unit through.

A body turning at rate ω(t) (rad/s, body frame) has the orientation
``R(t + dt) = R(t) · exp([ω dt]×)``: each step is a rotation about the body's own axes,
composed on the right. Over samples ``t_0 … t_{n-1}`` with rates ``ω_k``, step ``k``
turns by the rotation vector ``φ_k = ½(ω_k + ω_{k+1})·(t_{k+1} − t_k)`` (the trapezoid
rate held over the step), and the move's rotation is the ordered product

    R = exp(φ_0) · exp(φ_1) ⋯ exp(φ_{n-2}),

which maps vectors in the body axes at the end of the move into the body axes at its
start. Each exponential is a unit quaternion (:meth:`Rotation.from_rotvec
<scipy.spatial.transform.Rotation.from_rotvec>`); the product is a balanced tree of
vectorised Hamilton products, log₂ n levels, for many moves at once (shorter moves
padded with identity steps). Never Euler angles. For a constant rate it is exactly
``exp(ω·(t_{n-1} − t_0))``, whatever the steps.
"""

import numpy as np
from scipy.spatial.transform import Rotation

from station.domain.arrays import FloatArray

_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def quaternion_product(p: FloatArray, q: FloatArray) -> FloatArray:
    """Hamilton products ``p·q`` of scalar-last quaternions (..., 4): rotation q, then p.

    Written out by component, ``(p_w q_v + q_w p_v + p_v × q_v, p_w q_w − p_v·q_v)``: half
    the time of ``np.cross`` and a sum (the gyro matrix's fit calls it some 700 times a
    unit, most of the fit's time)."""
    px, py, pz, pw = np.moveaxis(p, -1, 0)
    qx, qy, qz, qw = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            pw * qx + qw * px + py * qz - pz * qy,
            pw * qy + qw * py + pz * qx - px * qz,
            pw * qz + qw * pz + px * qy - py * qx,
            pw * qw - px * qx - py * qy - pz * qz,
        ],
        axis=-1,
    )


def ordered_products(quaternions: FloatArray) -> FloatArray:
    """``q[:, 0] · q[:, 1] ⋯ q[:, -1]`` for each row of (moves, steps, 4), shape (moves, 4)."""
    level = quaternions
    while level.shape[1] > 1:
        if level.shape[1] % 2:
            pad = np.broadcast_to(_IDENTITY, (level.shape[0], 1, 4))
            level = np.concatenate([level, pad], axis=1)
        level = quaternion_product(level[:, 0::2], level[:, 1::2])
    if level.shape[1] == 0:
        return np.tile(_IDENTITY, (level.shape[0], 1))
    return np.asarray(level[:, 0], dtype=np.float64)


def ordered_product(steps: Rotation) -> Rotation:
    """``steps[0] · steps[1] ⋯ steps[-1]`` as one rotation (identity for no steps)."""
    if len(steps) == 0:
        return Rotation.identity()
    return Rotation.from_quat(ordered_products(steps.as_quat()[None])[0])


def step_rotvecs(t: FloatArray, rates: FloatArray) -> FloatArray:
    """The trapezoid steps ``½(ω_k + ω_{k+1})·(t_{k+1} − t_k)``, shape (n − 1, 3)."""
    return np.asarray(0.5 * (rates[:-1] + rates[1:]) * np.diff(t)[:, None], dtype=np.float64)


def integrate_steps(steps: FloatArray) -> Rotation:
    """One rotation per row of step rotation vectors (moves, steps, 3), zeros as padding."""
    moves, count = steps.shape[:2]
    if count == 0:
        return Rotation.from_quat(np.tile(_IDENTITY, (moves, 1)))
    quaternions = Rotation.from_rotvec(steps.reshape(-1, 3)).as_quat().reshape(moves, count, 4)
    return Rotation.from_quat(ordered_products(quaternions))


def integrate_rates(t: FloatArray, rates_rad_s: FloatArray) -> Rotation:
    """The rotation from the body at ``t[-1]`` to the body at ``t[0]``.

    Args:
        t: shape (n,), increasing sample times, s.
        rates_rad_s: shape (n, 3), body rates at those times, rad/s.
    """
    return integrate_steps(step_rotvecs(t, rates_rad_s)[None])[0]
