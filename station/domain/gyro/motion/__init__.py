"""The gyro matrix from the moves between still poses ([Tedaldi2014]_).

Model (``docs/calibration.md``): the gyros read ``m = b + K·ω`` (deg/s), ω the true
body rate in the calibrated accelerometer's frame. The bias b is the mean rate over
the still poses; K (nine elements: scales on the diagonal, misalignment off it) is
fitted so that each move's integrated rotation, from ``K⁻¹(m − b)`` on SO(3), carries
the gravity direction of the pose after the move into that of the pose before it.

Public surface::

    Move(t, rates_dps, gravity_before, gravity_after)          moves.py
        .problem() -> str | None          why it cannot be integrated (gaps, ...)
    fit_gyro_matrix(moves, bias_dps, *, min_moves, known_turn_deg) -> GyroMatrixFit
                                                                matrix_fit.py
        GyroMatrixFit.scale_matrix (3, 3), .standard_errors (3, 3),
        .bias_dps (3,), .used, .residual_deg, .residual_identity_deg,
        .unusable (UnusableMove(index, reason)), .condition_number, .to_dict()
    integrate_rates(t, rates_rad_s) -> Rotation                 integrate.py
    RecordedStream(t, accel_counts, gyro_dps)                   stream.py
    calibrate_stream(stream, model, *, thresholds=None, min_moves=6) -> StreamCalibration
        .stills, .accel (calibration.Solution), .gravity, .bias_dps, .moves, .gyro
    stream_thresholds(rate_hz, still_window_s)                  stream.py

Recorded streams of virtual units with known truth, for the tests and benchmarks, come
from the simulator (:mod:`station.simulator.recording`).

Errors::

    station.domain.errors.CalstationError
    ├── GyroMatrixError     the moves cannot determine K (too few usable, too alike)
    └── StreamError         a malformed stream, or too few still poses

.. [Tedaldi2014] D. Tedaldi, A. Pretto, E. Menegatti, "A robust and easy to implement
   method for IMU calibration without external equipments", ICRA 2014, pp. 3042–3049.
"""

from station.domain.gyro.motion.errors import GyroMatrixError, StreamError
from station.domain.gyro.motion.integrate import integrate_rates
from station.domain.gyro.motion.matrix_fit import GyroMatrixFit, UnusableMove, fit_gyro_matrix
from station.domain.gyro.motion.moves import GAP_FACTOR, Move
from station.domain.gyro.motion.stream import (
    RecordedStream,
    StreamCalibration,
    calibrate_stream,
    stream_thresholds,
)

__all__ = [
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
