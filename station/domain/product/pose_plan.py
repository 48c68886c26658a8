"""Whether a configured pose sequence can ever finish a unit.

A station's ``[run]`` settings name the poses to take and the verification pose. Some
choices accept every key and then stall or fail every unit: a pose listed twice (its
second capture is always "too close to pose 1, already taken"), the verification pose
among the fit poses, two poses closer than ``min_pose_separation_deg``, fewer poses
than the model's unknowns, or poses that cannot give a calibration at all (coplanar
gravity directions). These checks refuse them when the configuration is read, each
with a sentence a line engineer can act on.
"""

from collections.abc import Callable
from itertools import combinations

import numpy as np

from station.domain.calibration import UNKNOWNS, CalibrationError, Model, solve
from station.domain.sensors.sensor import NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G
from station.domain.signals.orientation import angle_deg
from station.domain.signals.poses import pose


def check_distinct(poses: tuple[str, ...]) -> None:
    """``ValueError`` when a pose is listed twice."""
    twice = next((name for i, name in enumerate(poses) if name in poses[:i]), None)
    if twice is not None:
        raise ValueError(
            f"{twice!r} is listed twice: its second capture would always be refused as "
            "too close to the first, and the unit could never finish"
        )


def check_verification(poses: tuple[str, ...], verification: str) -> None:
    """``ValueError`` when the verification pose is also a fit pose."""
    if verification in poses:
        raise ValueError(
            f"{verification!r} is also a calibration pose: the verification must be a pose "
            "the fit has not seen"
        )


def check_separation(poses: tuple[str, ...], separation_deg: float) -> None:
    """``ValueError`` when two of ``poses`` are closer than ``separation_deg``."""
    for a, b in combinations(poses, 2):
        apart = angle_deg(pose(a).gravity_body, pose(b).gravity_body)
        if apart < separation_deg:
            raise ValueError(
                f"poses {a!r} and {b!r} are {apart:.0f}° apart, under {separation_deg:g}°: "
                f"{b} would always be refused as too close to {a}"
            )


def check_solvable(poses: tuple[str, ...], model: Model) -> None:
    """``ValueError`` when ``poses`` cannot give a ``model`` calibration of a perfect unit."""
    if len(poses) < UNKNOWNS[model]:
        raise ValueError(
            f"the {model!r} model needs at least {UNKNOWNS[model]} calibration poses, "
            f"{len(poses)} are configured"
        )
    gravity = np.array([pose(n).gravity_body for n in poses])
    ideal = NOMINAL_OFFSET_COUNTS + NOMINAL_SENSITIVITY_COUNTS_PER_G * gravity
    try:
        solve(ideal, model)
    except CalibrationError as exc:
        raise ValueError(f"these poses cannot give a calibration: {exc}") from None


def check_plan(
    poses: tuple[str, ...], verification: str, separation_deg: float, model: Model
) -> None:
    """Every check above, as one ``ValueError`` naming the setting at fault."""
    everything = (*poses, verification)
    checks: list[tuple[str, Callable[[], None]]] = [
        ("poses", lambda: check_distinct(poses)),
        ("verification_pose", lambda: check_verification(poses, verification)),
        ("min_pose_separation_deg", lambda: check_separation(everything, separation_deg)),
        ("poses", lambda: check_solvable(poses, model)),
    ]
    for key, check in checks:
        try:
            check()
        except ValueError as exc:
            raise ValueError(f"{key}: {exc}") from None


def check_gyro_plan(model: Model, verification: str, last: str, separation_deg: float) -> None:
    """``ValueError`` when a plan with the gyro matrix could not give a good one.

    The gyro matrix is fitted against gravity directions from the calibrated
    accelerometer: a six-parameter fit, blind to the KXM52's 2 % cross-axis coupling,
    skews them enough to make K about 1.5 % wrong ([Tedaldi2014]_ procedure, measured
    with a reference solver). The verification move must turn the unit visibly.
    """
    if model != "nine":
        raise ValueError(
            "gyro: the gyro matrix needs model = 'nine': a six-parameter accelerometer "
            "skews the gravity directions K is fitted to by up to 1.5 %"
        )
    apart = angle_deg(pose(verification).gravity_body, pose(last).gravity_body)
    if apart < separation_deg:
        raise ValueError(
            f"gyro_verification_pose: {last!r} is {apart:.0f}° from the verification pose, "
            f"under {separation_deg:g}°: the verification move would barely turn the unit"
        )
