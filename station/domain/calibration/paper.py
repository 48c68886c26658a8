"""The six-position autocalibration of [Song2006]_, eq. 10, vectorised over units.

Model ([Song2006]_ eqs. 5, 7, 8): at rest, for every pose i, in counts,

    (a_xi − a_x0)²/s_x² + (a_yi − a_y0)²/s_y² + (a_zi − a_z0)²/s_z² = 1.

Multiplying by s_x² and subtracting pose i+1 from pose i gives five equations linear
in x = (a_x0, k1·a_y0, k2·a_z0, k1, k2), with k1 = s_x²/s_y², k2 = s_x²/s_z² (eq. 10):

    a_i·a_x0 + b_i·(k1·a_y0) + c_i·(k2·a_z0) + d_i·k1 + e_i·k2 = f_i,  i = 1…5
    a_i = 2(a_xi − a_x,i+1)   b_i = 2(a_yi − a_y,i+1)   c_i = 2(a_zi − a_z,i+1)
    d_i = −(a_yi² − a_y,i+1²) e_i = −(a_zi² − a_z,i+1²) f_i = a_xi² − a_x,i+1²

solved by Gaussian elimination with partial pivoting (LAPACK ``gesv`` through
:func:`numpy.linalg.solve`). Then s_x² follows from eq. 8 (averaged over the six
poses, which all give the same value for an exact solution), s_y = s_x/√k1 and
s_z = s_x/√k2.

The single-unit path :func:`solve_paper` is the batch path with K = 1, so both give
bit-identical results.
"""

from collections.abc import Sequence
from dataclasses import dataclass, fields
from enum import IntEnum
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from station.domain.arrays import FloatArray
from station.domain.calibration.errors import (
    CalibrationError,
    IllConditionedError,
    NonPositiveScaleError,
    TooFewPosesError,
)
from station.domain.calibration.geometry import (
    Finding,
    GeometryLimits,
    Screen,
    refuse_beyond_datasheet,
    screen,
    screen_error,
)
from station.domain.calibration.model import Calibration
from station.domain.calibration.residual import (
    MAX_CONDITION,
    condition_number,
    jacobian_six,
    normalise,
)
from station.domain.calibration.solution import Solution, quality_of
from station.domain.sensors.sensor import NOMINAL_SENSITIVITY_COUNTS_PER_G

PAPER_POSES = 6
#: Units solved together: bounds the batch path's memory and keeps it in cache.
CHUNK_UNITS = 1 << 12


class Outcome(IntEnum):
    """Result of one unit in a batch: solved, or why not."""

    OK = 0
    SCREENED_OUT = 1  # see ``PaperBatch.screen`` for the finding
    ILL_CONDITIONED = 2
    NON_POSITIVE_SCALE = 3


@dataclass(frozen=True, eq=False)
class PaperBatch:
    """Solutions of K units; rows of units whose ``outcome`` is not OK hold NaN.

    Attributes:
        offset: (K, 3) counts.  sensitivity: (K, 3) counts/g.
        k: (K, 2) the paper's k1, k2.  condition: (K,) cond(J), see
            :mod:`station.domain.calibration.residual`.
        outcome: (K,) :class:`Outcome` codes.  screen: the geometry screening.
    """

    offset: FloatArray
    sensitivity: FloatArray
    k: FloatArray
    condition: FloatArray
    outcome: NDArray[np.int64]
    screen: Screen


def eq10_system(poses: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The paper's eq. 10 for poses (K, 6, 3): matrix (K, 5, 5) and right side (K, 5)."""
    now, nxt = poses[:, :-1, :], poses[:, 1:, :]
    linear = 2.0 * (now - nxt)  # a_i, b_i, c_i
    squares = now**2 - nxt**2
    matrix = np.concatenate([linear, -squares[..., 1:]], axis=-1)  # d_i, e_i
    return matrix, squares[..., 0]  # f_i


def solve_paper_batch(
    poses: ArrayLike,
    limits: GeometryLimits = GeometryLimits(),
    max_condition: float = MAX_CONDITION,
) -> PaperBatch:
    """Solve eq. 10 for K units at once.

    Args:
        poses: shape (K, 6, 3), mean counts of six still poses per unit.
        limits: spacing and coverage bounds for the screening.
        max_condition: units whose system's condition number exceeds it are refused.
    """
    p = np.asarray(poses, dtype=np.float64)
    if p.ndim != 3 or p.shape[1:] != (PAPER_POSES, 3):
        raise CalibrationError(f"the paper's method takes K×6×3 poses, got shape {p.shape}")
    parts = [
        _solve_chunk(p[start : start + CHUNK_UNITS], limits, max_condition)
        for start in range(0, max(len(p), 1), CHUNK_UNITS)
    ]
    if len(parts) == 1:
        return parts[0]

    def joined(items: Sequence[object], name: str) -> Any:
        return np.concatenate([getattr(item, name) for item in items])

    screens = [part.screen for part in parts]
    screen = Screen(*(joined(screens, f.name) for f in fields(Screen)))
    arrays = {f.name: joined(parts, f.name) for f in fields(PaperBatch) if f.name != "screen"}
    return PaperBatch(**arrays, screen=screen)


def _solve_chunk(p: FloatArray, limits: GeometryLimits, max_condition: float) -> PaperBatch:
    """:func:`solve_paper_batch` on one chunk of units, small enough to stay in cache."""
    screened = screen(p, limits)
    outcome = np.where(screened.finding == Finding.OK, Outcome.OK, Outcome.SCREENED_OUT)

    # Screened-out units get a harmless stand-in so one bad unit cannot break the batch.
    usable = outcome == Outcome.OK
    work = np.where(usable[:, None, None], p, _STANDIN)
    x = _solve_eq10(*eq10_system(work))

    k = x[:, 3:5]
    offset = np.stack([x[:, 0], x[:, 1] / k[:, 0], x[:, 2] / k[:, 1]], axis=1)
    d = work - offset[:, None, :]
    sx2 = np.mean(
        d[..., 0] ** 2 + k[:, None, 0] * d[..., 1] ** 2 + k[:, None, 1] * d[..., 2] ** 2, axis=1
    )
    positive = (k > 0).all(axis=1) & (sx2 > 0)
    outcome[usable & ~positive] = Outcome.NON_POSITIVE_SCALE

    with np.errstate(invalid="ignore", divide="ignore"):
        sx = np.sqrt(sx2)
        sensitivity = np.stack([sx, sx / np.sqrt(k[:, 0]), sx / np.sqrt(k[:, 1])], axis=1)
    # cond(J) at the solution; units without one are measured at the nominal sensor
    # (the product's: its zero g and counts per g, in normalised counts).
    nominal = ~positive[:, None]
    sensor = limits.sensor
    condition = condition_number(
        jacobian_six(
            np.where(nominal, normalise(np.full(3, sensor.zero_g_counts)), normalise(offset)),
            np.where(nominal, sensor.counts_per_g, sensitivity) / NOMINAL_SENSITIVITY_COUNTS_PER_G,
            normalise(work),
        )
    )
    # Degenerate geometry is named before "no ellipsoid fits": on such poses noise alone
    # can make k1, k2 or s_x² negative, and the poses, not their stillness, are at fault.
    degenerate = usable & ~(condition <= max_condition)
    outcome[degenerate] = Outcome.ILL_CONDITIONED

    bad = outcome != Outcome.OK
    for arr in (offset, sensitivity, k):
        arr[bad] = np.nan
    condition[~usable | (~positive & ~degenerate)] = np.nan
    return PaperBatch(offset, sensitivity, k, condition, outcome.astype(np.int64), screened)


def solve_paper(
    poses: ArrayLike,
    limits: GeometryLimits = GeometryLimits(),
    max_condition: float = MAX_CONDITION,
) -> Solution:
    """Solve one unit's six poses (6, 3) by eq. 10; refuse with a clear message.

    Raises:
        TooFewPosesError: not exactly six poses.
        CalibrationError: a screening finding, an ill-conditioned system or a
            non-positive k1, k2 or s_x².
    """
    p = np.asarray(poses, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3:
        raise CalibrationError(f"poses must be an N×3 array of counts, got shape {p.shape}")
    if p.shape[0] != PAPER_POSES:
        raise TooFewPosesError(f"the paper's method takes exactly 6 poses, got {p.shape[0]}")
    batch = solve_paper_batch(p[None], limits, max_condition)
    outcome = Outcome(int(batch.outcome[0]))
    if outcome is Outcome.SCREENED_OUT:
        error = screen_error(batch.screen, 0, limits)
        assert error is not None
        raise error
    if outcome is Outcome.ILL_CONDITIONED:
        raise IllConditionedError(
            f"pose geometry degenerate: the poses are ill-conditioned (condition number "
            f"{batch.condition[0]:.3g} > {max_condition:.3g}): spread them over more directions"
        )
    if outcome is Outcome.NON_POSITIVE_SCALE:
        refuse_beyond_datasheet(p, limits.sensor)
        raise NonPositiveScaleError(
            "no ellipsoid fits these poses though their geometry is sound (k1, k2 or s_x² is not "
            "positive): a pose was not still, or poses are mislabelled"
        )
    calibration = Calibration.from_sensitivity(batch.offset[0], batch.sensitivity[0])
    return Solution(
        calibration=calibration,
        method="paper-eq10",
        quality=quality_of(calibration, p, float(batch.condition[0]), batch.screen),
        k=(float(batch.k[0, 0]), float(batch.k[0, 1])),
    )


def _solve_eq10(matrix: FloatArray, rhs: FloatArray) -> FloatArray:
    """x of eq. 10 for every unit (K, 5); NaN for a unit whose matrix is singular."""
    try:
        return np.asarray(np.linalg.solve(matrix, rhs[..., None])[..., 0], dtype=np.float64)
    except np.linalg.LinAlgError:  # some unit is exactly singular: solve one by one
        x = np.full(rhs.shape, np.nan)
        for i in range(matrix.shape[0]):
            try:
                x[i] = np.linalg.solve(matrix[i], rhs[i])
            except np.linalg.LinAlgError:
                continue
        return x


#: Six ideal poses (±1 g on each axis, nominal sensor) standing in for screened-out units.
_STANDIN = 2048.0 + 819.2 * np.array(
    [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=np.float64
)
