"""The run record's calibration part: what the solve found, and which poses it left out."""

import numpy as np

from station.domain.calibration import solve
from station.run.record import quality_metrics
from station.simulator.recording import pose_means, spread_directions
from station.simulator.sensor import SensorTruth


def test_a_pose_left_out_live_is_recorded_with_the_run() -> None:
    rng = np.random.default_rng(31)
    unit = SensorTruth.draw_accelerometer(rng, cross_axis=0.02)
    directions = spread_directions(12)
    poses = pose_means(unit, directions, 0.05, rng)
    poses[7] -= 80.0 * directions[7]  # the unit moved while pose 8 was taken
    quality = quality_metrics(solve(poses, "nine"), verification_error_mg=0.4)
    assert quality.excluded_poses == (7,)
    assert quality.residual_max_mg < 1.0  # over the poses kept


def test_a_clean_run_records_no_exclusion_field() -> None:
    rng = np.random.default_rng(32)
    poses = pose_means(SensorTruth.draw_accelerometer(rng), spread_directions(6), 0.05, rng)
    quality = quality_metrics(solve(poses), verification_error_mg=None)
    assert quality.excluded_poses is None
    assert "excluded_poses" not in quality.model_dump(exclude_none=True)
