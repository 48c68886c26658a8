"""Gyros: bias in the still poses, and the g-sensitivity error model of [Park2014]_.

Public surface::

    GyroErrorModel, term_names, regressors      model.py        the error model (eq. 4)
    GyroLog, read_log, write_log                log.py          rate-table / centrifuge CSV
    check_identifiability, IdentifiabilityReport, NotIdentifiableError
                                                identifiability.py
    fit_log, GyroFitReport                      fit.py          least squares + comparison
    AxisComparison                              comparison.py   nested models
    simulate_log, paper_truth, CentrifugePlan, Mount, Noise
                                                simulate.py     centrifuge + rate table
    compensate                                  compensation.py inverse of the model
    summarize_still_poses, GyroStillSummary     still.py        the station's still poses

The gyro matrix K from the moves between still poses ([Tedaldi2014]_) and the
recorded-stream calibration are the subpackage :mod:`station.domain.gyro.motion`.

The Fig. 10-style plot lives in :mod:`station.report.gyro_plot` (it imports matplotlib).

Errors::

    station.domain.errors.CalstationError
    ├── NotIdentifiableError    identifiability.py  the log cannot separate the terms asked for
    ├── motion.GyroMatrixError  motion/errors.py    the moves cannot determine K
    └── motion.StreamError      motion/errors.py    a recorded stream that cannot be calibrated
"""

from station.domain.gyro.comparison import AxisComparison
from station.domain.gyro.compensation import compensate
from station.domain.gyro.fit import GyroFitReport, fit_log
from station.domain.gyro.identifiability import (
    IdentifiabilityReport,
    NotIdentifiableError,
    check_identifiability,
)
from station.domain.gyro.log import GyroLog, read_log, write_log
from station.domain.gyro.model import GyroErrorModel, regressors, term_names
from station.domain.gyro.simulate import CentrifugePlan, Mount, Noise, paper_truth, simulate_log
from station.domain.gyro.still import GyroAxisStill, GyroStillSummary, summarize_still_poses

__all__ = [
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
