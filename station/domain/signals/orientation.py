"""Which way the putter lies, from its raw accelerometer counts.

Before calibration only the sensor's nominal scaling is known (for the putter: offset
2048 counts, 819.2 counts/g, [Song2006]_ Table 1; any product's:
:meth:`ZeroG.datasheet`). A unit at the datasheet's offset bounds (±207 counts,
±0.25 g on every axis) reads up to ~27° from the pose it lies in on nominal offsets
alone, more than the placement tolerance; refused there, a fixture's slot would wait
for a pose it already holds. So the station judges a pose on what it knows of each
axis' zero-g reading (:class:`ZeroG`): the datasheet's bounds until the axis is
measured, then the measurement. In an axis pose the two level axes read their own
offsets (off by the placement's tilt, a few degrees), so from the first capture on the
doubt shrinks to the placement. A unit is refused a pose only when no offset within
what is known explains the reading within the placement tolerance; the operator is told
which pose the station sees and how far it is from the one asked for.
"""

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Final

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.sensors.sensor_spec import PUTTER_SENSOR, SensorSpec
from station.domain.signals.poses import POSES, Pose

#: How far (degrees) the sensed gravity may be from a pose's and still count as it.
POSE_TOLERANCE_DEG = 25.0

#: How far from level (as a fraction of 1 g) an axis of a named pose may be and still
#: read its own offset there: the axis poses' level axes are exactly level.
_LEVEL: Final = 1e-6


#: The named poses and their gravity directions (one row each), computed once.
_NAMED: Final = tuple(POSES.values())
_NAMED_GRAVITY: Final = np.stack([p.gravity_body for p in _NAMED])


@dataclass(frozen=True)
class ZeroG:
    """Each axis' zero-g reading as known so far, how far off it may be, and the sensor's
    nominal sensitivity that turns the rest of a reading into g (counts, counts/g).

    :meth:`datasheet` gives a product's sensor's before any axis is measured (where none
    is given, the putter's: :data:`PUTTER_SENSOR`).
    """

    offset: FloatArray
    doubt: FloatArray
    counts_per_g: float

    @classmethod
    def datasheet(cls, sensor: SensorSpec) -> "ZeroG":
        """What ``sensor``'s datasheet says: its nominal zero g, within its spread."""
        return cls(
            offset=np.full(3, sensor.zero_g_counts),
            doubt=np.full(3, sensor.zero_g_spread_counts),
            counts_per_g=sensor.counts_per_g,
        )

    @classmethod
    def measured(
        cls, captured: Iterable[tuple[Pose, FloatArray]], sensor: SensorSpec = PUTTER_SENSOR
    ) -> "ZeroG":
        """Each axis' mean over the captured poses where it lies level, else ``sensor``'s
        datasheet's.

        ``captured`` pairs a taken pose with its mean counts (3,).
        """
        sums = np.zeros(3)
        counts = np.zeros(3)
        for pose, mean in captured:
            level = np.abs(pose.gravity_body) < _LEVEL
            sums += np.where(level, np.asarray(mean, dtype=np.float64), 0.0)
            counts += level
        known = counts > 0
        nominal = cls.datasheet(sensor)
        return cls(
            offset=np.where(known, sums / np.maximum(counts, 1), nominal.offset),
            doubt=np.where(known, 0.0, nominal.doubt),
            counts_per_g=sensor.counts_per_g,
        )


def gravity_direction(accel_counts: FloatArray, zero_g: ZeroG | None = None) -> FloatArray:
    """Unit vector of the sensed gravity reaction (body axes) from mean raw counts (3,)."""
    known = zero_g or ZeroG.datasheet(PUTTER_SENSOR)
    g = (np.asarray(accel_counts, dtype=np.float64) - known.offset) / known.counts_per_g
    norm = _length(g)
    return g / norm if norm > 0 else np.array([0.0, 0.0, 0.0])


def _length(v: FloatArray) -> float:
    """Euclidean length of ``v``: what :func:`numpy.linalg.norm` computes for a vector
    (the square root of its dot product with itself), to the bit, without the wrapper's
    overhead (the live view senses a window at every pass, per slot)."""
    return math.sqrt(float(v @ v))


def angle_deg(a: FloatArray, b: FloatArray) -> float:
    """Angle between two unit vectors, degrees."""
    return math.degrees(math.acos(min(1.0, max(-1.0, float(a @ b)))))


@dataclass(frozen=True)
class Sensed:
    """The pose nearest to the sensed gravity, and the angle to it.

    ``slack``: per axis, how far the direction may be off from the offsets' doubt
    (in units of the sensed vector's length).
    """

    direction: FloatArray
    nearest: Pose
    nearest_deg: float
    slack: FloatArray = field(default_factory=lambda: np.zeros(3))

    def matches(self, pose: Pose, tolerance_deg: float = POSE_TOLERANCE_DEG) -> bool:
        """Whether the unit may lie in ``pose`` within the tolerance.

        The direction's part across the pose is first moved toward the pose by as much as
        each axis' doubt allows: the smallest tilt the reading admits is judged.
        """
        target = pose.gravity_body
        across = self.direction - float(self.direction @ target) * target
        closest = self.direction - np.minimum(np.maximum(across, -self.slack), self.slack)
        norm = _length(closest)
        return norm > 0 and angle_deg(closest / norm, target) <= tolerance_deg


def sense(
    accel_counts: FloatArray,
    candidates: tuple[Pose, ...] | None = None,
    zero_g: ZeroG | None = None,
) -> Sensed:
    """The named pose (of ``candidates``, default all) nearest to the mean counts."""
    known = zero_g or ZeroG.datasheet(PUTTER_SENSOR)
    g = (np.asarray(accel_counts, dtype=np.float64) - known.offset) / known.counts_per_g
    norm = _length(g)
    if norm == 0:
        direction, slack = np.zeros(3), np.zeros(3)
    else:
        direction, slack = g / norm, known.doubt / known.counts_per_g / norm
    pool = candidates if candidates is not None else _NAMED
    gravity = _NAMED_GRAVITY if candidates is None else np.stack([p.gravity_body for p in pool])
    # One product for every pose (the live view asks at every pass, per slot).
    cosines = gravity @ direction
    best = int(np.argmax(cosines))
    return Sensed(direction, pool[best], angle_deg(direction, pool[best].gravity_body), slack)
