"""One entry point: the right method for the model and the number of poses."""

import numpy as np
from numpy.typing import ArrayLike

from station.domain.calibration.consistency import solve_consistent
from station.domain.calibration.geometry import GeometryLimits
from station.domain.calibration.model import Model
from station.domain.calibration.paper import PAPER_POSES, solve_paper
from station.domain.calibration.residual import MAX_CONDITION
from station.domain.calibration.solution import Solution


def solve(
    poses: ArrayLike,
    model: Model = "six",
    limits: GeometryLimits = GeometryLimits(),
    max_condition: float = MAX_CONDITION,
    max_residual_counts: float | None = None,
) -> Solution:
    """Calibrate from N still poses, shape (N, 3), mean counts.

    ``model="six"``: the paper's eq. 10 for exactly six poses, least squares for more.
    ``model="nine"``: the 9-parameter least-squares fit (N ≥ 9). A least-squares fit
    checks its studentised residuals against ``max_residual_counts`` (default: the
    model's, :mod:`station.domain.calibration.consistency`), leaving out one inconsistent pose
    when there are enough poses to tell which, refusing otherwise.
    """
    p = np.asarray(poses, dtype=np.float64)
    if model == "six" and p.ndim == 2 and p.shape[0] == PAPER_POSES:
        return solve_paper(p, limits, max_condition)
    return solve_consistent(p, model, limits, max_condition, max_residual_counts)
