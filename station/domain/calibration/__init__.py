"""Accelerometer calibration from still poses, after [Song2006]_.

Public surface::

    solve(poses, model)        the right method for the model and pose count
    solve_paper(poses)         the paper's six-position eq. 10
    solve_paper_batch(poses)   eq. 10 for K units at once, (K, 6, 3)
    solve_least_squares(...)   6- or 9-parameter maximum-likelihood fit, N ≥ 6 / 9
    solve_consistent(...)      least squares that leaves out one inconsistent pose
    solve_classic(plus, minus) the ±1 g baseline, eqs. 2 and 3
    apply(calibration, raw)    counts → g
    accelerometer_budget(...)  the GUM budget of a solve's coefficients (U, k = 2)
    gyro_bias_uncertainty(...) U of the gyro bias from the still poses
    gyro_bias_repeatability(b) the bias' spread across power-on sessions (S, 3)

.. [Song2006] C.-M. Song, "Autocalibration Method of Three-axis Micromachined
   Accelerometers", 2006.
"""

from station.domain.calibration.classic import solve_classic
from station.domain.calibration.consistency import DEFAULT_RESIDUAL_LIMIT_COUNTS, solve_consistent
from station.domain.calibration.errors import (
    BeyondDatasheetError,
    CalibrationError,
    CoplanarPosesError,
    DuplicatePoseError,
    IllConditionedError,
    InconsistentPosesError,
    InvalidValueError,
    NonPositiveScaleError,
    NotCountsError,
    RailValueError,
    TooFewPosesError,
)
from station.domain.calibration.geometry import GeometryLimits, coverage, pair_angles_deg
from station.domain.calibration.least_squares import UNKNOWNS, solve_least_squares
from station.domain.calibration.model import Calibration, Model, apply
from station.domain.calibration.paper import Outcome, solve_paper, solve_paper_batch
from station.domain.calibration.solution import MIN_DOF_SHOWN, SENSITIVITY_CONVENTION, Solution
from station.domain.calibration.solve import solve
from station.domain.calibration.uncertainty import (
    COVERAGE_FACTOR,
    Uncertainty,
    accelerometer_budget,
    gyro_bias_repeatability,
    gyro_bias_uncertainty,
    gyro_matrix_uncertainty,
)

__all__ = [
    "COVERAGE_FACTOR",
    "DEFAULT_RESIDUAL_LIMIT_COUNTS",
    "MIN_DOF_SHOWN",
    "SENSITIVITY_CONVENTION",
    "UNKNOWNS",
    "BeyondDatasheetError",
    "Calibration",
    "CalibrationError",
    "CoplanarPosesError",
    "DuplicatePoseError",
    "GeometryLimits",
    "IllConditionedError",
    "InconsistentPosesError",
    "InvalidValueError",
    "Model",
    "NonPositiveScaleError",
    "NotCountsError",
    "Outcome",
    "RailValueError",
    "Solution",
    "TooFewPosesError",
    "Uncertainty",
    "accelerometer_budget",
    "apply",
    "coverage",
    "gyro_bias_repeatability",
    "gyro_bias_uncertainty",
    "gyro_matrix_uncertainty",
    "pair_angles_deg",
    "solve",
    "solve_classic",
    "solve_consistent",
    "solve_least_squares",
    "solve_paper",
    "solve_paper_batch",
]
