"""Screening of pose sets before a solve: values, spacing and coverage.

Every check is vectorised over units: poses come as a (K, N, 3) array of mean counts
(K units, N poses each). The spacing and coverage measures use only differences
between poses, so they do not depend on the unknown offsets:

* **angle between poses** — two still poses i, j with gravity directions u_i, u_j are
  |a_i − a_j| ≈ s·|u_i − u_j| = 2·s·sin(θ/2) counts apart, so
  θ = 2·asin(|a_i − a_j| / 2s) with the nominal sensitivity s;
* **coverage** — √(λ_min/λ_max) of the covariance of the pose means: 1 when the
  poses span all directions equally (e.g. ±1 g on each axis), 0 when they lie in one
  plane, where an ellipsoid through them is not unique (the system of [Song2006]_
  eq. 10 degenerates when the poses do not span the sphere).
"""

from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from numpy.typing import NDArray

from station.arrays import FloatArray
from station.calibration.errors import (
    CalibrationError,
    CoplanarPosesError,
    DuplicatePoseError,
    InvalidValueError,
    RailValueError,
    TooFewPosesError,
)
from station.sensor import (
    ADC_MAX,
    ADC_MIN,
    AXES,
    NOMINAL_OFFSET_COUNTS,
    NOMINAL_SENSITIVITY_COUNTS_PER_G,
)

#: Default minimum angle between two poses' gravity directions, degrees.
MIN_POSE_ANGLE_DEG = 10.0
#: Default minimum coverage √(λ_min/λ_max) of the pose set.
MIN_COVERAGE = 0.2


@dataclass(frozen=True)
class GeometryLimits:
    """Bounds on a pose set's spacing and coverage."""

    min_angle_deg: float = MIN_POSE_ANGLE_DEG
    min_coverage: float = MIN_COVERAGE


class Finding(IntEnum):
    """The first problem the screen found in a unit's poses (``OK`` when none)."""

    OK = 0
    NON_FINITE = 1
    AT_RAIL = 2
    DUPLICATE = 3
    COPLANAR = 4


@dataclass(frozen=True)
class Screen:
    """Per-unit screening result; arrays have shape (K,).

    ``pose`` and ``other`` locate the finding: the pose index and, for AT_RAIL the
    axis, for DUPLICATE the earlier pose it repeats (−1 where not applicable).
    """

    finding: NDArray[np.int64]
    pose: NDArray[np.int64]
    other: NDArray[np.int64]
    min_angle_deg: FloatArray
    coverage: FloatArray


def chord_to_angle_deg(chord: FloatArray) -> FloatArray:
    """Angle (degrees) between two poses' gravity directions from their distance in counts."""
    half = np.clip(chord / (2.0 * NOMINAL_SENSITIVITY_COUNTS_PER_G), 0.0, 1.0)
    return np.asarray(np.degrees(2.0 * np.arcsin(half)), dtype=np.float64)


def pair_angles_deg(poses: FloatArray) -> FloatArray:
    """Angles (degrees) between every two poses' gravity directions, shape (..., N, N)."""
    chord = np.linalg.norm(poses[..., :, None, :] - poses[..., None, :, :], axis=-1)
    return chord_to_angle_deg(chord)


def coverage(poses: FloatArray) -> FloatArray:
    """√(λ_min/λ_max) of the pose means' covariance, shape (...,); 0 for coplanar poses."""
    centred = poses - poses.mean(axis=-2, keepdims=True)
    scatter = np.swapaxes(centred, -1, -2) @ centred
    eig = np.linalg.eigvalsh(scatter)
    ratio = np.divide(
        eig[..., 0], eig[..., -1], out=np.zeros_like(eig[..., 0]), where=eig[..., -1] > 0
    )
    return np.asarray(np.sqrt(np.clip(ratio, 0.0, 1.0)), dtype=np.float64)


def screen(poses: FloatArray, limits: GeometryLimits = GeometryLimits()) -> Screen:
    """Screen K units' poses, shape (K, N, 3); the first finding per unit wins."""
    k, n, _ = poses.shape
    units = np.arange(k)
    finding = np.zeros(k, dtype=np.int64)
    where = np.full(k, -1, dtype=np.int64)
    other = np.full(k, -1, dtype=np.int64)

    def mark(
        code: Finding, bad: NDArray[np.bool_], pose: NDArray[np.int64], extra: NDArray[np.int64]
    ) -> None:
        new = bad & (finding == Finding.OK)
        finding[new] = code
        where[new] = pose[new]
        other[new] = extra[new]

    flat = poses.reshape(k, n * 3)
    finite = np.isfinite(flat)
    if not finite.all():
        bad = ~finite
        first = bad.argmax(axis=1)
        mark(Finding.NON_FINITE, bad[units, first], first // 3, first % 3)
        flat = np.where(finite, flat, NOMINAL_OFFSET_COUNTS)
    rail = (flat <= ADC_MIN) | (flat >= ADC_MAX)
    first = rail.argmax(axis=1)
    mark(Finding.AT_RAIL, rail[units, first], first // 3, first % 3)
    if rail.any():  # values beyond the ADC's range would only overflow what follows
        flat = np.where(rail, NOMINAL_OFFSET_COUNTS, flat)

    clean = flat.reshape(k, n, 3)
    earlier, later = np.triu_indices(n, 1)
    diff = clean[:, later, :] - clean[:, earlier, :]
    chord2 = np.einsum("kpi,kpi->kp", diff, diff)
    closest = chord2.argmin(axis=1)
    min_angle = chord_to_angle_deg(np.sqrt(chord2[units, closest]))
    mark(Finding.DUPLICATE, min_angle < limits.min_angle_deg, later[closest], earlier[closest])

    cover = coverage(clean)
    none = np.full(k, -1, dtype=np.int64)
    mark(Finding.COPLANAR, cover < limits.min_coverage, none, none)
    return Screen(finding, where, other, min_angle, cover)


def screen_error(
    screen_result: Screen, unit: int, limits: GeometryLimits
) -> CalibrationError | None:
    """The refusal for one unit's screening finding, or ``None`` when it passed."""
    code = Finding(int(screen_result.finding[unit]))
    pose = int(screen_result.pose[unit])
    other = int(screen_result.other[unit])
    if code is Finding.NON_FINITE:
        return InvalidValueError(
            f"pose {pose + 1}: {AXES[other]} is not a finite number", pose=pose
        )
    if code is Finding.AT_RAIL:
        return RailValueError(
            f"pose {pose + 1}: {AXES[other]} is at the ADC rail ({ADC_MIN} or {ADC_MAX} counts): "
            "the axis is saturated",
            pose=pose,
        )
    if code is Finding.DUPLICATE:
        angle = float(screen_result.min_angle_deg[unit])
        return DuplicatePoseError(
            f"pose {pose + 1} repeats pose {other + 1}: {angle:.1f}° apart, "
            f"at least {limits.min_angle_deg:g}° needed",
            pose=pose,
        )
    if code is Finding.COPLANAR:
        cover = float(screen_result.coverage[unit])
        return CoplanarPosesError(
            f"the poses lie near one plane (coverage {cover:.3f}, at least {limits.min_coverage:g} "
            "needed): add poses with gravity along the missing direction"
        )
    return None


def check_poses(
    poses: FloatArray, min_poses: int, limits: GeometryLimits = GeometryLimits()
) -> Screen:
    """Screen one unit's poses, shape (N, 3), raising the first refusal found.

    Raises:
        TooFewPosesError: fewer than ``min_poses`` poses.
        CalibrationError: any finding of :func:`screen`.
    """
    if poses.ndim != 2 or poses.shape[1] != 3:
        raise CalibrationError(f"poses must be an N×3 array of counts, got shape {poses.shape}")
    if poses.shape[0] < min_poses:
        raise TooFewPosesError(
            f"{poses.shape[0]} poses given, this model needs at least {min_poses}"
        )
    result = screen(poses[None], limits)
    error = screen_error(result, 0, limits)
    if error is not None:
        raise error
    return result
