"""How a station runs its units: the poses, their tolerances, stillness and the model.

Part of the station's configuration (:class:`station.loop.config.StationConfig`); read by
every step of a unit's run (:class:`station.run.unit_run.UnitRun`).

Run plans ship beside the limits profiles: ``station/domain/profiles/plans.toml`` holds
one ``[plans.NAME]`` table per profile that is not run the default way (six poses,
[Song2006]_). :func:`shipped_plan` gives the table of a profile name, which the station's
configuration takes as its ``[run]`` defaults, so that ``--profile whole-unit`` chooses
the limits and the poses, model and gyro calibration together.
"""

import tomllib
from functools import cache
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from station.domain.calibration import Model
from station.domain.product.capture_budget import AdaptiveCapture, WindowPolicy
from station.domain.product.limits import LimitsProfile
from station.domain.product.pose_plan import check_gyro_plan, check_plan
from station.domain.sensors.sensor_spec import SensorSpec
from station.domain.signals.orientation import POSE_TOLERANCE_DEG
from station.domain.signals.poses import CALIBRATION_POSES, POSES, VERIFICATION_POSE
from station.domain.signals.stillness import StillnessThresholds
from station.domain.toml_text import shipped_text


class RunSettings(BaseModel):
    """How a station runs its units (from the station's configuration)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    poses: tuple[str, ...] = Field(CALIBRATION_POSES, min_length=6)
    verification_pose: str = VERIFICATION_POSE
    pose_tolerance_deg: float = Field(POSE_TOLERANCE_DEG, gt=0, lt=90)
    min_pose_separation_deg: float = Field(
        30.0, gt=0, description="a capture this close to an earlier pose is refused"
    )
    stillness: StillnessThresholds = StillnessThresholds()
    pose_timeout_s: float = Field(30.0, gt=0, description="device time before 'not still'")
    model: Model = "six"
    capture: Literal["fixed", "adaptive"] = Field(
        "fixed",
        description="fixed: every window stillness.window_samples long; adaptive: a "
        "window ends when its mean meets the limits' accuracy budget ([run.adaptive])",
    )
    adaptive: AdaptiveCapture = AdaptiveCapture()
    gyro: bool = Field(
        False,
        description="fit the gyro matrix K from the moves between the poses, write it "
        "into the unit and check it on the verification move [Tedaldi2014]",
    )
    gyro_verification_pose: str = Field(
        "face_up", description="where the verification move takes the unit (with gyro)"
    )

    @property
    def sensor(self) -> SensorSpec:
        """The product's sensor whose counts the run judges (its stillness thresholds')."""
        return self.stillness.sensor

    def window_policy(self, profile: LimitsProfile) -> WindowPolicy:
        """How long a pose's still window is, under ``profile``'s limits."""
        if self.capture == "adaptive":
            return WindowPolicy.adaptive(self.adaptive, profile)
        return WindowPolicy.fixed(self.stillness.window_samples)

    @field_validator("poses", "verification_pose", "gyro_verification_pose")
    @classmethod
    def _known_poses(cls, value: str | tuple[str, ...]) -> str | tuple[str, ...]:
        names = (value,) if isinstance(value, str) else value
        unknown = [n for n in names if n not in POSES]
        if unknown:
            raise ValueError(f"unknown pose {unknown[0]!r}; known: {', '.join(POSES)}")
        return value

    @model_validator(mode="after")
    def _can_finish(self) -> "RunSettings":
        check_plan(self.poses, self.verification_pose, self.min_pose_separation_deg, self.model)
        if self.gyro:
            check_gyro_plan(
                self.model,
                self.verification_pose,
                self.gyro_verification_pose,
                self.min_pose_separation_deg,
            )
        return self


@cache
def _plans() -> dict[str, dict[str, Any]]:
    plans: dict[str, dict[str, Any]] = tomllib.loads(shipped_text("plans.toml"))["plans"]
    return plans


def shipped_plan(profile: object) -> dict[str, Any] | None:
    """The ``[run]`` settings shipped for limits profile ``profile``, or None."""
    if not isinstance(profile, str):
        return None
    plan = _plans().get(profile)
    return dict(plan) if plan is not None else None
