"""The gyro-matrix package's public surface is pinned (the live station builds on it)."""

import station.domain.gyro.motion


def test_public_names() -> None:
    assert sorted(station.domain.gyro.motion.__all__) == [
        "GAP_FACTOR",
        "GyroMatrixError",
        "GyroMatrixFit",
        "Move",
        "RecordedStream",
        "StreamCalibration",
        "StreamError",
        "UnusableMove",
        "calibrate_stream",
        "fit_gyro_matrix",
        "integrate_rates",
        "stream_thresholds",
    ]
    for name in station.domain.gyro.motion.__all__:
        assert getattr(station.domain.gyro.motion, name) is not None
