"""Taking still poses from a streaming putter: stillness detection and the pose record."""

from station.run.acquisition.errors import (
    AcquisitionError,
    LinkQualityError,
    NotStillError,
    SaturatedAxisError,
)
from station.run.acquisition.pose import PoseAcquisition, PoseResult, acquire_pose
from station.run.acquisition.stillness import (
    StillnessDetector,
    StillnessThresholds,
    WindowVerdict,
    judge_window,
)

__all__ = [
    "AcquisitionError",
    "LinkQualityError",
    "NotStillError",
    "PoseAcquisition",
    "PoseResult",
    "SaturatedAxisError",
    "StillnessDetector",
    "StillnessThresholds",
    "WindowVerdict",
    "acquire_pose",
    "judge_window",
]
