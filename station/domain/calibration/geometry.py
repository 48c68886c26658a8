"""Screening of pose sets before a solve: values, spacing and coverage.

Every check is vectorised over units: poses come as a (K, N, 3) array of mean counts
(K units, N poses each), and every one takes memory linear in N (the closest pose of
each pose comes from a k-d tree beyond a few dozen poses, never from an N×N table).

Every bound in counts is the sensor's (:class:`GeometryLimits`' ``sensor``,
:mod:`station.domain.sensors.sensor_spec`; the putter's by default).

The values are checked first, each refusal naming its real cause:

* **not counts** — every value within ±:data:`NOT_COUNTS_BELOW`: acceleration in g or
  m/s² (|a| ≈ 1 or 9.8), not ADC counts (0…4095 for the putter);
* **at the rail** — a mean within :func:`rail_margin_counts` of 0 or the ADC's largest
  count: samples of that axis sat at the converter's end, the mean is clipped;
* **beyond the datasheet** — an axis further from its nominal zero g than any unit of the
  sensor can read at 1 g (:func:`datasheet_reach_counts`): the unit was moving, or the
  sensor is out of spec.
  Not a refusal of its own (an out-of-spec unit still calibrates, and fails on its
  limits with the values measured), but the cause named when the poses are refused
  (:func:`refuse_beyond_datasheet`).

The spacing and coverage measures use only differences between poses, so they do not
depend on the unknown offsets:

* **angle between poses** — two still poses i, j with gravity directions u_i, u_j are
  |a_i − a_j| ≈ s·|u_i − u_j| = 2·s·sin(θ/2) counts apart, so
  θ = 2·asin(|a_i − a_j| / 2s) with the sensor's nominal sensitivity s;
* **coverage** — √(λ_min/λ_max) of the covariance of the pose means: 1 when the
  poses span all directions equally (e.g. ±1 g on each axis), 0 when they lie in one
  plane, where an ellipsoid through them is not unique (the system of [Song2006]_
  eq. 10 degenerates when the poses do not span the sphere).
"""

import math
from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from numpy.typing import NDArray

from station.domain.arrays import FloatArray
from station.domain.calibration.errors import (
    BeyondDatasheetError,
    CalibrationError,
    CoplanarPosesError,
    DuplicatePoseError,
    InvalidValueError,
    NotCountsError,
    RailValueError,
    TooFewPosesError,
)
from station.domain.sensors.sensor import ADC_MIN, AXES
from station.domain.sensors.sensor_spec import PUTTER_SENSOR, SensorSpec

#: Default minimum angle between two poses' gravity directions, degrees.
MIN_POSE_ANGLE_DEG = 10.0
#: Default minimum coverage √(λ_min/λ_max) of the pose set.
MIN_COVERAGE = 0.2
#: A pose mean this close to a rail is clipped: with a sample spread of twice what the
#: stillness limit allows (9.8 mg, 8 counts of the putter: the worst case a judged window
#: passes, as :mod:`.consistency` takes it), samples 2σ above such a mean sat at the rail.
#: 19.5 mg: 16 counts of the putter's 819.2 counts/g.
RAIL_MARGIN_G = 0.01953125
#: Largest cross-axis coupling of a unit the datasheet allows for: 5 %.
CROSS_AXIS_MAX = 0.05


def rail_margin_counts(sensor: SensorSpec) -> float:
    """How close to a rail of ``sensor``'s ADC a pose mean is clipped, counts."""
    return sensor.counts(RAIL_MARGIN_G)


def datasheet_reach_counts(sensor: SensorSpec) -> int:
    """Farthest an axis of ``sensor`` can read from its nominal zero g at 1 g, counts: the
    datasheet's zero-g spread plus its largest sensitivity with the largest cross-axis
    (:data:`CROSS_AXIS_MAX`, ·√(1 + 2·0.05²)), plus the rail margin for noise (the
    putter: 207 + 819.2 · 1.05 · 1.0025 + 16 = 1 085 counts)."""
    largest = sensor.counts_per_g * (1 + sensor.sensitivity_tolerance)
    return round(
        sensor.zero_g_spread_counts
        + largest * math.sqrt(1 + 2 * CROSS_AXIS_MAX**2)
        + rail_margin_counts(sensor)
    )


#: Every value within ± this: the file holds g or m/s², never counts of a still pose.
NOT_COUNTS_BELOW = 20.0
#: Up to this many poses the closest pair comes from all pairs at once (vectorised over
#: units); beyond it, from a k-d tree, one unit at a time.
PAIRWISE_MAX_POSES = 32


@dataclass(frozen=True)
class GeometryLimits:
    """Bounds on a pose set's spacing and coverage, and the sensor whose counts the poses
    are (its rails, nominal zero g and sensitivity, datasheet spreads)."""

    min_angle_deg: float = MIN_POSE_ANGLE_DEG
    min_coverage: float = MIN_COVERAGE
    sensor: SensorSpec = PUTTER_SENSOR


class Finding(IntEnum):
    """The first problem the screen found in a unit's poses (``OK`` when none)."""

    OK = 0
    NON_FINITE = 1
    AT_RAIL = 2
    DUPLICATE = 3
    COPLANAR = 4
    NOT_COUNTS = 5


@dataclass(frozen=True)
class Screen:
    """Per-unit screening result; arrays have shape (K,).

    ``pose`` and ``other`` locate the finding: the pose index and, for AT_RAIL the
    axis, for DUPLICATE the other pose of the closest pair (−1 where not applicable).
    ``closest`` holds the closest pair (K, 2), ``near`` how many poses lie closer than
    :data:`MIN_POSE_ANGLE_DEG` to another pose: reported, and refused only where the
    caller refuses duplicates (the paper's exactly determined eq. 10).
    """

    finding: NDArray[np.int64]
    pose: NDArray[np.int64]
    other: NDArray[np.int64]
    min_angle_deg: FloatArray
    coverage: FloatArray
    closest: NDArray[np.int64]
    near: NDArray[np.int64]


def chord_to_angle_deg(
    chord: FloatArray, counts_per_g: float = PUTTER_SENSOR.counts_per_g
) -> FloatArray:
    """Angle (degrees) between two poses' gravity directions from their distance in counts
    of a sensor of ``counts_per_g``."""
    half = np.clip(chord / (2.0 * counts_per_g), 0.0, 1.0)
    return np.asarray(np.degrees(2.0 * np.arcsin(half)), dtype=np.float64)


def pair_angles_deg(
    poses: FloatArray, counts_per_g: float = PUTTER_SENSOR.counts_per_g
) -> FloatArray:
    """Angles (degrees) between every two poses' gravity directions, shape (..., N, N),
    from counts of a sensor of ``counts_per_g``."""
    chord = np.linalg.norm(poses[..., :, None, :] - poses[..., None, :, :], axis=-1)
    return chord_to_angle_deg(chord, counts_per_g)


def coverage(poses: FloatArray) -> FloatArray:
    """√(λ_min/λ_max) of the pose means' covariance, shape (...,); 0 for coplanar poses."""
    centred = poses - poses.mean(axis=-2, keepdims=True)
    scatter = np.swapaxes(centred, -1, -2) @ centred
    eig = np.linalg.eigvalsh(scatter)
    ratio = np.divide(
        eig[..., 0], eig[..., -1], out=np.zeros_like(eig[..., 0]), where=eig[..., -1] > 0
    )
    return np.asarray(np.sqrt(np.clip(ratio, 0.0, 1.0)), dtype=np.float64)


def screen(
    poses: FloatArray, limits: GeometryLimits = GeometryLimits(), *, refuse_duplicates: bool = True
) -> Screen:
    """Screen K units' poses, shape (K, N, 3); the first finding per unit wins.

    ``refuse_duplicates``: whether a pair closer than the minimum angle is a finding
    (eq. 10 with six poses degenerates on it) or only counted in ``near`` (least squares).
    """
    k, n, _ = poses.shape
    sensor = limits.sensor
    units = np.arange(k)
    finding = np.zeros(k, dtype=np.int64)
    where = np.full(k, -1, dtype=np.int64)
    other = np.full(k, -1, dtype=np.int64)
    none = np.full(k, -1, dtype=np.int64)

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
        flat = np.where(finite, flat, sensor.zero_g_counts)
    small = np.all(np.abs(flat) < NOT_COUNTS_BELOW, axis=1)
    mark(Finding.NOT_COUNTS, small, none, none)
    margin = rail_margin_counts(sensor)
    rail = (flat <= ADC_MIN + margin) | (flat >= sensor.adc_max - margin)
    first = rail.argmax(axis=1)
    mark(Finding.AT_RAIL, rail[units, first], first // 3, first % 3)
    if rail.any():  # values beyond the ADC's range would only overflow what follows
        flat = np.where(rail, sensor.zero_g_counts, flat)

    clean = flat.reshape(k, n, 3)
    nearest, neighbour = _nearest(clean, finding != Finding.OK)
    closest = nearest.argmin(axis=1)
    pair = np.stack([closest, neighbour[units, closest]], axis=1)
    pair.sort(axis=1)
    min_angle = chord_to_angle_deg(nearest[units, closest], sensor.counts_per_g)
    # Counted against the documented near-duplicate angle whatever the caller refuses
    # (least squares refuses none, min_angle_deg 0): the count the JSON and the screen
    # report beside min_angle_deg means the same in every solve.
    near = (chord_to_angle_deg(nearest, sensor.counts_per_g) < MIN_POSE_ANGLE_DEG).sum(axis=1)
    if refuse_duplicates:
        mark(Finding.DUPLICATE, min_angle < limits.min_angle_deg, pair[:, 1], pair[:, 0])

    cover = coverage(clean)
    mark(Finding.COPLANAR, cover < limits.min_coverage, none, none)
    return Screen(finding, where, other, min_angle, cover, pair, near.astype(np.int64))


def _nearest(poses: FloatArray, refused: NDArray[np.bool_]) -> tuple[FloatArray, NDArray[np.int64]]:
    """Distance (counts) from every pose to its closest other pose, and which one it is.

    Both (K, N). Few poses: all pairs at once, vectorised over units; many: a k-d tree
    per unit (:class:`scipy.spatial.cKDTree`), memory linear in N, skipping the units
    already ``refused`` (their stand-in values may all coincide, a k-d tree's worst
    case); theirs read ∞.
    """
    k, n, _ = poses.shape
    if n <= PAIRWISE_MAX_POSES:
        diff = poses[:, :, None, :] - poses[:, None, :, :]
        chord2 = np.einsum("kijd,kijd->kij", diff, diff)
        chord2[:, np.arange(n), np.arange(n)] = np.inf
        neighbour = chord2.argmin(axis=2)
        nearest = np.sqrt(np.take_along_axis(chord2, neighbour[..., None], axis=2)[..., 0])
        return nearest, neighbour.astype(np.int64)
    nearest = np.full((k, n), np.inf)
    neighbour = np.zeros((k, n), dtype=np.int64)
    for unit in np.flatnonzero(~refused):
        nearest[unit], neighbour[unit] = _nearest_one(poses[unit])
    return nearest, neighbour


def _nearest_one(points: FloatArray) -> tuple[FloatArray, NDArray[np.int64]]:
    """:func:`_nearest` of one unit's many poses (N, 3): a k-d tree over the distinct
    poses (identical ones would pile into one leaf, the tree's quadratic worst case);
    a pose repeated exactly is 0 from its twin."""
    distinct, first, inverse = np.unique(points, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.reshape(-1)
    nearest = np.zeros(len(points))
    neighbour = np.zeros(len(points), dtype=np.int64)
    if len(distinct) > 1:
        # Imported here: scipy.spatial takes ~0.5 s to load, and only many poses need it
        # (the server and the command line import this module at start).
        from scipy.spatial import cKDTree

        distance, index = cKDTree(distinct).query(distinct, k=2)
        nearest = np.asarray(distance)[:, 1][inverse]
        neighbour = first[np.asarray(index)[:, 1]][inverse]
    order = np.argsort(inverse, kind="stable")  # twins side by side
    group = inverse[order]
    twin_next = np.flatnonzero(group[1:] == group[:-1])
    one, other = order[twin_next], order[twin_next + 1]
    nearest[one] = nearest[other] = 0.0
    neighbour[one], neighbour[other] = other, one
    return nearest, neighbour


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
    if code is Finding.NOT_COUNTS:
        return NotCountsError(
            f"the values look like acceleration in g or m/s² (all within ±{NOT_COUNTS_BELOW:g}), "
            f"not ADC counts ({ADC_MIN}…{limits.sensor.adc_max}): give the raw counts of each pose"
        )
    if code is Finding.AT_RAIL:
        return RailValueError(
            f"pose {pose + 1}: {AXES[other]} is at the ADC rail (within "
            f"{rail_margin_counts(limits.sensor):g} counts of {ADC_MIN} or "
            f"{limits.sensor.adc_max}): the axis is saturated, its mean clipped",
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
    poses: FloatArray,
    min_poses: int,
    limits: GeometryLimits = GeometryLimits(),
    *,
    refuse_duplicates: bool = False,
) -> Screen:
    """Screen one unit's poses, shape (N, 3), raising the first refusal found.

    Near-duplicate poses are refused only with ``refuse_duplicates``; otherwise the
    screen counts them (least squares loses nothing by them but their information).

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
    result = screen(poses[None], limits, refuse_duplicates=refuse_duplicates)
    error = screen_error(result, 0, limits)
    if error is not None:
        raise error
    return result


def refuse_beyond_datasheet(poses: FloatArray, sensor: SensorSpec = PUTTER_SENSOR) -> None:
    """Raise :class:`BeyondDatasheetError` for the first pose (N, 3) with an axis further
    from ``sensor``'s zero g than any unit of it reads at 1 g: called before refusing the
    poses for another reason, as it is the likelier cause (a moving unit, or an
    out-of-spec sensor)."""
    reach = datasheet_reach_counts(sensor)
    beyond = np.abs(poses - sensor.zero_g_counts) > reach
    if beyond.any():
        pose, axis = (int(i) for i in np.argwhere(beyond)[0])
        raise BeyondDatasheetError(
            f"pose {pose + 1}: {AXES[axis]} reads beyond the datasheet's reach at 1 g "
            f"({sensor.zero_g_counts:g} ± {reach} counts): the unit was "
            "moving, or the sensor is out of spec",
            pose=pose,
        )
