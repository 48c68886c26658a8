"""Which way the putter lies, from its raw accelerometer counts.

Before calibration only nominal scaling is known (offset 2048 counts, 819.2
counts/g, [Song2006]_ Table 1), good to about 15° — ample to tell the named poses apart,
which are 90° from each other. The operator is told which pose the station sees and
how far it is from the one asked for.
"""

from dataclasses import dataclass

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.poses import POSES, Pose
from station.domain.sensor import NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G

#: How far (degrees) the sensed gravity may be from a pose's and still count as it.
POSE_TOLERANCE_DEG = 25.0


def gravity_direction(accel_counts: FloatArray) -> FloatArray:
    """Unit vector of the sensed gravity reaction (body axes) from mean raw counts (3,)."""
    g = (
        np.asarray(accel_counts, dtype=np.float64) - NOMINAL_OFFSET_COUNTS
    ) / NOMINAL_SENSITIVITY_COUNTS_PER_G
    norm = float(np.linalg.norm(g))
    return g / norm if norm > 0 else np.array([0.0, 0.0, 0.0])


def angle_deg(a: FloatArray, b: FloatArray) -> float:
    """Angle between two unit vectors, degrees."""
    return float(np.degrees(np.arccos(np.clip(float(a @ b), -1.0, 1.0))))


@dataclass(frozen=True)
class Sensed:
    """The pose nearest to the sensed gravity, and the angle to it."""

    direction: FloatArray
    nearest: Pose
    nearest_deg: float

    def matches(self, pose: Pose, tolerance_deg: float = POSE_TOLERANCE_DEG) -> bool:
        """Whether the unit lies in ``pose`` within the tolerance."""
        return angle_deg(self.direction, pose.gravity_body) <= tolerance_deg


def sense(accel_counts: FloatArray, candidates: tuple[Pose, ...] | None = None) -> Sensed:
    """The named pose (of ``candidates``, default all) nearest to the mean counts."""
    direction = gravity_direction(accel_counts)
    pool = candidates if candidates is not None else tuple(POSES.values())
    # One product for every pose (the live view asks ~40 times a second).
    cosines = np.stack([p.gravity_body for p in pool]) @ direction
    best = int(np.argmax(cosines))
    return Sensed(direction, pool[best], angle_deg(direction, pool[best].gravity_body))
