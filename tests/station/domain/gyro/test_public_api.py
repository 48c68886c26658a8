"""The package's public surface is pinned."""

import station.domain.gyro


def test_public_names() -> None:
    assert sorted(station.domain.gyro.__all__) == [
        "AxisComparison",
        "CentrifugePlan",
        "GyroAxisStill",
        "GyroErrorModel",
        "GyroFitReport",
        "GyroLog",
        "GyroStillSummary",
        "IdentifiabilityReport",
        "Mount",
        "Noise",
        "NotIdentifiableError",
        "check_identifiability",
        "compensate",
        "fit_log",
        "paper_truth",
        "read_log",
        "regressors",
        "simulate_log",
        "summarize_still_poses",
        "term_names",
        "write_log",
    ]
    for name in station.domain.gyro.__all__:
        assert getattr(station.domain.gyro, name) is not None
