"""The putter's named poses, as rotations of its body frame.

Body frame of the putter (the sensor board is mounted to it):

- x: along the face, heel to toe;
- y: the face normal, pointing to the target;
- z: along the shaft, from the head to the grip.

A pose is the rotation ``R`` that takes body-frame vectors to the world frame
(x, y horizontal, z up). At rest the accelerometer senses the reaction to gravity,
+1 g along world up, i.e. ``R⁻¹ · (0, 0, 1)`` in its own axes: that is
:attr:`Pose.gravity_body`. Any turn about the vertical leaves it unchanged, which is
why the six calibration poses need no precise jig ([Song2006]_).
"""

from dataclasses import dataclass
from functools import cached_property
from types import MappingProxyType
from typing import Final

import numpy as np
from scipy.spatial.transform import Rotation

from station.domain.arrays import FloatArray

UP: Final = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class Pose:
    """A named orientation of the putter and what the operator is told to do."""

    name: str
    rotation: Rotation
    instruction: str

    @cached_property  # read ~20,000 times a unit by the live view: computed once per pose
    def gravity_body(self) -> FloatArray:
        """Unit vector of the sensed gravity reaction in body axes (in g)."""
        gravity = np.asarray(self.rotation.inv().apply(UP), dtype=np.float64)
        gravity.setflags(write=False)  # shared by every reader of this pose
        return gravity


def _pose(name: str, euler_xyz_deg: tuple[float, float, float], instruction: str) -> Pose:
    return Pose(name, Rotation.from_euler("xyz", euler_xyz_deg, degrees=True), instruction)


def _corner(signs: tuple[int, int, int]) -> Pose:
    """The putter in a corner cradle: gravity's reaction along the cube diagonal ``signs``.

    Named by the three parts that point up (toe or heel, face or back, grip or head); the
    rotation is the smallest that lifts that diagonal to world up.
    """
    parts = (("toe", "heel"), ("face", "back"), ("grip", "head"))
    up = [pair[0] if sign > 0 else pair[1] for pair, sign in zip(parts, signs, strict=True)]
    diagonal = np.array(signs, dtype=np.float64) / np.sqrt(3.0)
    rotation = Rotation.align_vectors([UP], [diagonal])[0]
    words = f"{up[0]}, {up[1]} and {up[2]}"
    return Pose("_".join((*up, "up")), rotation, f"put the putter in the corner cradle, {words} up")


#: The corner poses of the whole-unit plan: the cube diagonals at least 60° from the
#: verification pose (the nine-parameter fit and the gyro moves need directions off the
#: axes).
CORNER_SIGNS: Final = ((1, 1, -1), (1, -1, 1), (1, -1, -1), (-1, 1, 1), (-1, 1, -1), (-1, -1, 1))


#: Every named pose, by name.
POSES: Final = MappingProxyType(
    {
        p.name: p
        for p in (
            _pose("shaft_up", (0, 0, 0), "stand the putter on its head, shaft pointing up"),
            _pose("shaft_down", (180, 0, 0), "hold the putter upside down, grip on the floor"),
            _pose("toe_up", (0, -90, 0), "lay the putter on its heel, toe pointing up"),
            _pose("toe_down", (0, 90, 0), "rest the putter on its toe, heel pointing up"),
            _pose("face_up", (90, 0, 0), "lay the putter on its back, face pointing up"),
            _pose("face_down", (-90, 0, 0), "lay the putter face down"),
            _pose(
                "verify_tilted",
                (35.0, -40.0, 0),
                "put the putter in the tilted verification cradle",
            ),
            *(_corner(signs) for signs in CORNER_SIGNS),
        )
    }
)

#: The six calibration poses, in the order the operator is asked for them.
CALIBRATION_POSES: Final = ("face_up", "face_down", "toe_up", "toe_down", "shaft_up", "shaft_down")
#: The extra pose that checks a calibration: no axis aligned with gravity.
VERIFICATION_POSE: Final = "verify_tilted"


def pose(name: str) -> Pose:
    """The pose called ``name``; ``KeyError`` names the known ones."""
    try:
        return POSES[name]
    except KeyError:
        raise KeyError(f"unknown pose {name!r}; known: {', '.join(POSES)}") from None
