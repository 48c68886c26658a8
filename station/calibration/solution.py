"""What a solve returns: the calibration and how far to trust it."""

from dataclasses import dataclass
from typing import Literal

import numpy as np

from station.arrays import FloatArray
from station.calibration.geometry import Screen
from station.calibration.model import Calibration, apply

Method = Literal["paper-eq10", "least-squares"]


@dataclass(frozen=True, eq=False)
class StandardErrors:
    """1-σ standard errors of a redundant fit (N poses > unknowns), counts and counts/g."""

    offset: FloatArray
    sensitivity: FloatArray


@dataclass(frozen=True, eq=False)
class Quality:
    """How well the calibration explains its poses and how sound their geometry is.

    Attributes:
        pose_g: shape (N,), calibrated |g| of each pose (1 for a perfect fit).
        residual_rms_mg, residual_max_mg: RMS and largest |(|g| − 1)| over the poses, mg.
        condition_number: cond(J) of the residual's Jacobian in normalised counts
            (:mod:`station.calibration.residual`); parameter errors grow with it.
        coverage: √(λ_min/λ_max) of the poses' spread, 0 (one plane) … 1 (all directions).
        min_angle_deg: smallest angle between two poses' gravity directions.
    """

    pose_g: FloatArray
    residual_rms_mg: float
    residual_max_mg: float
    condition_number: float
    coverage: float
    min_angle_deg: float


@dataclass(frozen=True, eq=False)
class Solution:
    """A calibration, the method that found it and its quality."""

    calibration: Calibration
    method: Method
    quality: Quality
    standard_errors: StandardErrors | None = None
    k: tuple[float, float] | None = None

    @property
    def poses(self) -> int:
        """Number of poses solved from."""
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
        }
        if self.standard_errors is not None:
            se = self.standard_errors
            payload["standard_errors"] = {
                "offset": dict(zip("xyz", se.offset.tolist(), strict=True)),
                "sensitivity": dict(zip("xyz", se.sensitivity.tolist(), strict=True)),
            }
        return payload


def quality_of(
    calibration: Calibration, poses: FloatArray, condition_number: float, screened: Screen
) -> Quality:
    """Residuals of ``calibration`` over ``poses`` (N, 3) plus the geometry measures."""
    pose_g = np.linalg.norm(apply(calibration, poses), axis=1)
    residual_mg = (pose_g - 1.0) * 1000.0
    return Quality(
        pose_g=pose_g,
        residual_rms_mg=float(np.sqrt(np.mean(residual_mg**2))),
        residual_max_mg=float(np.max(np.abs(residual_mg))),
        condition_number=float(condition_number),
        coverage=float(screened.coverage[0]),
        min_angle_deg=float(screened.min_angle_deg[0]),
    )
