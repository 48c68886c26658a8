"""What a solve returns: the calibration and how far to trust it.

Residuals are given in g (``pose_g``: the calibrated |g| of each pose) and in counts,
(|g| − 1)·819.2, the misfit along gravity at the nominal sensitivity. The **studentised
residual** of a fitted pose is its residual over √(1 − h_i), h_i its leverage
(:func:`station.domain.calibration.residual.leverage`): the misfit it would show had it not
pulled the fit toward itself; under noise σ per axis it has standard deviation σ for
every pose, which makes one limit fair to all of them.
"""

from dataclasses import dataclass
from typing import Literal

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.calibration.geometry import Screen
from station.domain.calibration.model import Calibration, Model, apply, xyz
from station.domain.sensors.sensor_spec import PUTTER_SENSOR

Method = Literal["paper-eq10", "least-squares"]

#: Degrees of freedom from which the screen prints "±" (Student's t95 = 3.18 at 3).
MIN_DOF_SHOWN = 3
#: What the JSON ``sensitivity`` is, per model: for nine it depends on the convention
#: that makes C unique (upper-triangular, i.e. x is the reference axis and y lies in the
#: x-y plane), and differs from each axis' own counts/g by up to ~0.8 counts/g at 2 %
#: cross-axis coupling.
SENSITIVITY_CONVENTION = {
    "six": "1/diag(C), C diagonal",
    "nine": "1/diag(C), C upper-triangular (x reference axis, y in the x-y plane)",
}


@dataclass(frozen=True, eq=False)
class CoefficientErrors:
    """1-σ standard errors of a redundant fit (N poses > unknowns), counts and counts/g.

    ``dof`` = N − p, the degrees of freedom of σ̂: with one or two, σ̂ rests on one or two
    residuals and the errors are rough (a 95 % interval is 12.7 or 4.3 of them, Student's
    t), so the screen shows them only from :data:`MIN_DOF_SHOWN` on.
    """

    offset: FloatArray
    sensitivity: FloatArray
    dof: int = 0


@dataclass(frozen=True, eq=False)
class Quality:
    """How well the calibration explains its poses and how sound their geometry is.

    Attributes:
        pose_g: shape (N,), calibrated |g| of each pose (1 for a perfect fit).
        residual_rms_mg, residual_max_mg: RMS and largest |(|g| − 1)| over the poses, mg.
        condition_number: cond(J) of the residual's Jacobian in normalised counts
            (:mod:`station.domain.calibration.residual`); parameter errors grow with it.
        coverage: √(λ_min/λ_max) of the poses' spread, 0 (one plane) … 1 (all directions).
        min_angle_deg: smallest angle between two poses' gravity directions.
        closest_pair: the two poses (0-based) that angle is between.
        near_duplicates: poses closer than the minimum angle to another pose: they add
            little information, and only eq. 10 with exactly six poses refuses them.
        studentised_counts: shape (N,), each fitted pose's studentised residual in
            counts (NaN for an excluded pose); ``None`` without redundancy.
    """

    pose_g: FloatArray
    residual_rms_mg: float
    residual_max_mg: float
    condition_number: float
    coverage: float
    min_angle_deg: float
    closest_pair: tuple[int, int] = (0, 1)
    near_duplicates: int = 0
    studentised_counts: FloatArray | None = None

    @property
    def studentised_max_counts(self) -> float | None:
        """The largest |studentised residual| of the fitted poses, counts."""
        t = self.studentised_counts
        return None if t is None else float(np.nanmax(np.abs(t)))


@dataclass(frozen=True, eq=False)
class Solution:
    """A calibration, the method that found it and its quality."""

    calibration: Calibration
    method: Method
    quality: Quality
    standard_errors: CoefficientErrors | None = None
    k: tuple[float, float] | None = None
    excluded: tuple[int, ...] = ()
    residual_limit_counts: float | None = None
    checked_with: Model | None = None

    @property
    def poses(self) -> int:
        """Number of poses given (the excluded ones included)."""
        return int(self.quality.pose_g.shape[0])

    def to_dict(self) -> dict[str, object]:
        """JSON-ready summary (the ``calstation solve --json`` shape)."""
        cal = self.calibration.to_dict()
        q = self.quality
        payload: dict[str, object] = {
            "model": cal["model"],
            "method": self.method,
            "poses": self.poses,
            "offset": cal["offset"],
            "sensitivity": cal["sensitivity"],
            "matrix": cal["matrix"],
            "residual_rms_mg": q.residual_rms_mg,
            "residual_max_mg": q.residual_max_mg,
            "condition_number": q.condition_number,
            "coverage": q.coverage,
            "min_angle_deg": q.min_angle_deg,
            "pose_g": q.pose_g.tolist(),
            "k1": None if self.k is None else self.k[0],
            "k2": None if self.k is None else self.k[1],
            "standard_errors": None,
            "sensitivity_convention": SENSITIVITY_CONVENTION[self.calibration.model],
            "excluded": [pose + 1 for pose in self.excluded],
            "residual_limit_counts": self.residual_limit_counts,
            "residual_checked_with": self.checked_with,
            "studentised_max_counts": q.studentised_max_counts,
            "closest_pair": [pose + 1 for pose in q.closest_pair],
            "near_duplicates": q.near_duplicates,
        }
        if self.standard_errors is not None:
            se = self.standard_errors
            payload["standard_errors"] = {
                "offset": xyz(se.offset),
                "sensitivity": xyz(se.sensitivity),
                "dof": se.dof,
            }
        return payload


def quality_of(
    calibration: Calibration,
    poses: FloatArray,
    condition_number: float,
    screened: Screen,
    leverage: FloatArray | None = None,
    counts_per_g: float = PUTTER_SENSOR.counts_per_g,
) -> Quality:
    """Residuals of ``calibration`` over ``poses`` (N, 3) plus the geometry measures.

    ``leverage`` (N,) of a redundant fit gives the studentised residuals, in counts of a
    sensor of ``counts_per_g`` (nominal).
    """
    pose_g = np.linalg.norm(apply(calibration, poses), axis=1)
    residual_mg = (pose_g - 1.0) * 1000.0
    studentised = None
    if leverage is not None and len(poses) > round(float(leverage.sum())):
        spare = np.clip(1.0 - leverage, 0.0, None)
        counts = (pose_g - 1.0) * counts_per_g
        studentised = np.divide(
            counts, np.sqrt(spare), out=np.zeros_like(counts), where=spare > LEVERAGE_FLOOR
        )
    return Quality(
        pose_g=pose_g,
        residual_rms_mg=float(np.sqrt(np.mean(residual_mg**2))),
        residual_max_mg=float(np.max(np.abs(residual_mg))),
        condition_number=float(condition_number),
        coverage=float(screened.coverage[0]),
        min_angle_deg=float(screened.min_angle_deg[0]),
        closest_pair=(int(screened.closest[0, 0]), int(screened.closest[0, 1])),
        near_duplicates=int(screened.near[0]),
        studentised_counts=studentised,
    )


#: A pose with 1 − h below this determines a direction of the fit alone: its residual
#: is zero whatever it reads, and it has no studentised residual (0 is reported).
LEVERAGE_FLOOR = 1e-9
