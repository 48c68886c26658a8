"""The gyro matrix K from the moves between still poses ([Tedaldi2014]_).

Model: a gyro triad reads ``m = b + K·ω + n`` (deg/s), with ω the true body rate in
the calibrated accelerometer's frame, b the bias (from the still poses) and K the
3×3 scale-and-misalignment matrix (identity for a perfect triad). For a trial K each
move's corrected rates ``ω̂ = K⁻¹(m − b)`` are integrated on SO(3)
(:func:`~station.domain.gyro.motion.integrate.integrate_rates`) into the rotation R from the
body at the move's end to the body at its start, which must carry the end pose's
gravity direction into the start pose's::

    r_j(K) = R_j(K) · u_after,j − u_before,j  ≈  0.

The nine elements of K minimise Σ|r_j|² (:func:`scipy.optimize.least_squares`, from
K = I). Each move constrains two degrees of freedom (a turn about gravity is invisible
to it), so five moves would just determine it; at least six usable moves are asked
for (:data:`MIN_MOVES`), about varied axes. Standard errors
are ``σ·√diag((JᵀJ)⁻¹)`` with σ² = Σ|r|² / (2·moves − 9); a move's residual is the
angle between ``R·u_after`` and ``u_before``, in degrees.

**Known turns.** A move that ends where it began after a whole turn about the vertical
(Ferraris' 360° about each axis, [Ferraris1995]_, as imucal records them) constrains
nothing above: gravity's direction is the same at both ends, whatever K. When the
recording declares the angle of such turns (``known_turn_deg``), a move whose two still
poses lie within :data:`SAME_POSE_DEG` of each other and whose raw rates sweep more than
half that angle is taken as one. The corrected rates must then sweep exactly that angle,
``|K⁻¹·Σφ_raw| = θ`` (the sum of the steps' rotation vectors is the angle times the axis
for a turn about a fixed axis), one equation a turn, in radians beside the gravity
residuals' unit-vector lengths. Its axis is left free: a hand's turn is not exactly about
the vertical, nor about one axis throughout, and asking the summed rotation vector to lie
along the vertical as well (three equations a turn) pulled K off the moves between faces
(imucal's session, held out: 0.757° RMS against 0.672° with the angle alone,
``docs/benchmarks.md``).
"""

from dataclasses import dataclass
from typing import Final

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.gyro.motion.errors import GyroMatrixError, StreamError
from station.domain.gyro.motion.integrate import integrate_steps, step_rotvecs
from station.domain.gyro.motion.moves import Move

#: Unknowns of K.
K_UNKNOWNS: Final = 9
#: Constraints one move gives (two: the turn about gravity is invisible).
CONSTRAINTS_PER_MOVE: Final = 2
#: The fewest usable moves fitted: 2 × 6 = 12 equations for 9 unknowns. Five moves (one
#: spare equation) determine K in principle but not in practice: over 200 simulated
#: six-pose units the worst came out 128 % off (docs/benchmarks.md).
MIN_MOVES: Final = 6
#: Above this condition number of the Jacobian the moves do not determine K.
MAX_CONDITION: Final = 1e6
#: A move whose still poses lie this close (degrees) returns to where it began: with a
#: declared turn angle, it is a known turn.
SAME_POSE_DEG: Final = 20.0


@dataclass(frozen=True)
class UnusableMove:
    """A move left out of the fit, and why."""

    index: int
    reason: str


@dataclass(frozen=True, eq=False)
class GyroMatrixFit:
    """The fitted gyro matrix and how well it explains the moves.

    Attributes:
        scale_matrix: shape (3, 3), K in ``m = b + K·ω``.
        standard_errors: shape (3, 3), 1-σ of each element of K (six moves or more
            leave at least three degrees of freedom).
        bias_dps: shape (3,), the bias the rates were corrected with, deg/s.
        used: indices of the moves fitted, in order.
        residual_deg: shape (len(used),), each used move's residual with the fitted K.
        residual_identity_deg: the same with K = I (no gyro calibration), for contrast.
        unusable: the moves left out and why.
        condition_number: cond(J) of the fit's Jacobian at the solution.
        directions: shape (len(used), 2, 3), each used move's gravity directions before
            and after it, as fitted.
        direction_gain: shape (3, 3, len(used), 2, 3), ∂K/∂(u_before, u_after) of each
            used move to first order (``−(JᵀJ)⁻¹Jᵀ·∂r/∂u``, ∂r_j/∂u_before = −I,
            ∂r_j/∂u_after = R_j): how an error of the gravity directions moves K, the
            moves' geometry of the uncertainty budget
            (:func:`station.domain.calibration.uncertainty.gyro_matrix_uncertainty`).
    """

    scale_matrix: FloatArray
    standard_errors: FloatArray
    bias_dps: FloatArray
    used: tuple[int, ...]
    residual_deg: FloatArray
    residual_identity_deg: FloatArray
    unusable: tuple[UnusableMove, ...]
    condition_number: float
    directions: FloatArray
    direction_gain: FloatArray
    #: Moves fitted as known turns (indices into the moves), and each one's swept angle
    #: with the fitted K, degrees.
    known_turns: tuple[int, ...] = ()
    known_turn_swept_deg: tuple[float, ...] = ()

    @property
    def residual_rms_deg(self) -> float:
        """RMS of the used moves' residuals, degrees."""
        return float(np.sqrt(np.mean(self.residual_deg**2)))

    @property
    def residual_identity_rms_deg(self) -> float:
        """RMS of the same moves' residuals with K = I, degrees."""
        return float(np.sqrt(np.mean(self.residual_identity_deg**2)))

    def to_dict(self) -> dict[str, object]:
        """JSON-ready (the ``"gyro"`` object of ``calstation solve --stream --json``)."""
        return {
            "bias_dps": self.bias_dps.tolist(),
            "scale_matrix": self.scale_matrix.tolist(),
            "scale_matrix_standard_errors": self.standard_errors.tolist(),
            "moves": len(self.used) + len(self.unusable),
            "moves_used": list(self.used),
            "residual_deg": self.residual_deg.tolist(),
            "residual_rms_deg": self.residual_rms_deg,
            "residual_identity_deg": self.residual_identity_deg.tolist(),
            "unusable_moves": [{"move": u.index, "reason": u.reason} for u in self.unusable],
            "condition_number": self.condition_number,
            "known_turns": list(self.known_turns),
            "known_turn_swept_deg": list(self.known_turn_swept_deg),
        }


class _Moves:
    """The usable moves' raw steps, bias removed, in arrays of (moves, steps, 3).

    The corrected rates are linear in the raw ones, so each step's rotation vector for
    a trial K is the raw step's ``K⁻¹·φ_raw``: one product per evaluation. Moves are
    grouped by their step count rounded up to a power of two and padded with zero
    steps (identity rotations) to it, so the arrays hold under twice the steps.
    """

    def __init__(
        self, moves: list[Move], bias_dps: FloatArray, known_turn_deg: float | None = None
    ) -> None:
        raw = [step_rotvecs(m.t, np.radians(m.rates_dps - bias_dps)) for m in moves]
        #: Each move's raw steps summed: ``K⁻¹·swept`` is its rotation vector for a turn
        #: about a fixed axis.
        swept = np.array([r.sum(axis=0) for r in raw]).reshape(-1, 3)
        returns = np.array([m.gravity_turn_deg < SAME_POSE_DEG for m in moves], dtype=bool)
        #: What each move that returns to the pose it left sweeps, degrees (its raw rates).
        self.returned_deg = np.degrees(np.linalg.norm(swept[returns], axis=1))
        self.turns = (
            np.flatnonzero(
                returns & (np.linalg.norm(swept, axis=1) > np.radians(known_turn_deg) / 2)
            )
            if known_turn_deg is not None
            else np.array([], dtype=int)
        )
        self.swept = swept[self.turns]
        #: The angle each known turn's corrected rates must sweep, radians.
        self.turn_rad = np.radians(known_turn_deg or 0.0)
        widths = [1 << max(0, len(r) - 1).bit_length() for r in raw]
        self.groups: list[tuple[list[int], FloatArray]] = []
        for width in sorted(set(widths)):
            members = [i for i, w in enumerate(widths) if w == width]
            steps = np.zeros((len(members), width, 3))
            for row, i in zip(steps, members, strict=True):
                row[: len(raw[i])] = raw[i]
            self.groups.append((members, steps))
        self.before = np.array([m.gravity_before for m in moves])
        self.after = np.array([m.gravity_after for m in moves])

    def carried(self, k: FloatArray) -> FloatArray:
        """Each move's ``R(K)·u_after``, shape (moves, 3)."""
        k_inv_t = np.linalg.inv(k).T
        out = np.empty_like(self.after)
        for members, steps in self.groups:
            out[members] = integrate_steps(steps @ k_inv_t).apply(self.after[members])
        return out

    def swept_rad(self, k: FloatArray) -> FloatArray:
        """Each known turn's angle swept by the corrected rates, radians."""
        return np.asarray(np.linalg.norm(self.swept @ np.linalg.inv(k).T, axis=1))

    def rotations(self, k: FloatArray) -> FloatArray:
        """Each move's rotation R(K) as a matrix, shape (moves, 3, 3)."""
        k_inv_t = np.linalg.inv(k).T
        out = np.empty((len(self.after), 3, 3))
        for members, steps in self.groups:
            out[members] = integrate_steps(steps @ k_inv_t).as_matrix()
        return out

    def residual(self, theta: FloatArray) -> FloatArray:
        k = theta.reshape(3, 3)
        gravity = (self.carried(k) - self.before).ravel()
        if not len(self.turns):
            return np.asarray(gravity)
        return np.concatenate((gravity, self.swept_rad(k) - self.turn_rad))

    def angles_deg(self, k: FloatArray) -> FloatArray:
        carried = self.carried(k)
        cos = np.clip(np.sum(carried * self.before, axis=1), -1.0, 1.0)
        return np.asarray(np.degrees(np.arccos(cos)), dtype=np.float64)


#: A declared whole turn is found when a returning move's raw rates sweep within this
#: fraction of its angle (a gyro's scale error is a few per cent; a wrong unit or a turn
#: of another size is far beyond it).
TURN_TOLERANCE: Final = 0.25


def fit_gyro_matrix(
    moves: list[Move],
    bias_dps: FloatArray,
    *,
    min_moves: int = MIN_MOVES,
    known_turn_deg: float | None = None,
) -> GyroMatrixFit:
    """Fit K from ``moves`` with the gyro bias ``bias_dps`` (3,) removed.

    ``known_turn_deg``: the angle of every whole turn the recording holds (module
    docstring, *Known turns*); None: no turn is known.

    Moves with gaps or too few samples are left out and named in ``unusable``.
    ``min_moves`` below :data:`MIN_MOVES` (down to 5) is for measuring why it is the
    default.

    Raises:
        ValueError: ``min_moves`` below 5 (no degree of freedom left).
        StreamError: ``known_turn_deg`` given and no returning move sweeps within
            :data:`TURN_TOLERANCE` of it (the declaration contradicts the recording).
        GyroMatrixError: fewer
            than ``min_moves`` usable moves, or moves whose axes
            do not determine all nine elements (condition number above
            :data:`MAX_CONDITION`).
    """
    if CONSTRAINTS_PER_MOVE * min_moves <= K_UNKNOWNS:
        raise ValueError(f"min_moves {min_moves} leaves no degree of freedom for K")
    bias = np.asarray(bias_dps, dtype=np.float64)
    problems = [move.problem() for move in moves]
    used = [index for index, problem in enumerate(problems) if problem is None]
    unusable = [UnusableMove(i, why) for i, why in enumerate(problems) if why is not None]
    if len(used) < min_moves:
        why = "; ".join(f"move {u.index}: {u.reason}" for u in unusable)
        raise GyroMatrixError(
            f"gyro matrix needs {min_moves} usable moves, got {len(used)} of {len(moves)}"
            + (f" ({why})" if why else "")
        )
    data = _Moves([moves[i] for i in used], bias, known_turn_deg)
    if (
        known_turn_deg is not None
        and not (np.abs(data.returned_deg / known_turn_deg - 1.0) <= TURN_TOLERANCE).any()
    ):
        swept = ", ".join(f"{a:.0f}°" for a in data.returned_deg) or "none"
        raise StreamError(
            f"whole turns of {known_turn_deg:g}° declared, but no move that returns within "
            f"{SAME_POSE_DEG:g}° to the pose it left sweeps within "
            f"{TURN_TOLERANCE:.0%} of it (theirs: {swept}): leave out --known-turn-deg, "
            "or declare the angle the turns sweep"
        )
    # Imported here: scipy.optimize is a sixth of the station's imports (0.16 s), and
    # only the whole unit's profile fits K.
    from scipy.optimize import least_squares

    result = least_squares(data.residual, np.eye(3).ravel(), method="lm", x_scale=1.0)
    k = result.x.reshape(3, 3)
    jac = np.asarray(result.jac)
    singular = np.linalg.svd(jac, compute_uv=False)
    condition = float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")
    if not np.isfinite(condition) or condition > MAX_CONDITION:
        raise GyroMatrixError(
            f"gyro matrix not determined: the {len(used)} moves turn about too few axes "
            f"(condition number {condition:.3g} > {MAX_CONDITION:g})"
        )
    dof = CONSTRAINTS_PER_MOVE * len(used) + len(data.turns) - K_UNKNOWNS
    sigma2 = float(result.fun @ result.fun) / dof
    normal_inv = np.linalg.inv(jac.T @ jac)
    errors = np.sqrt(np.diag(normal_inv) * sigma2).reshape(3, 3)
    # ∂r/∂u: r_j = R_j·u_after,j − u_before,j, so −I on u_before and R_j on u_after; a
    # known turn's r = |K⁻¹·Σφ| − θ does not depend on the gravity directions.
    moved, turns = len(used), len(data.turns)
    dr_du = np.zeros((3 * moved + turns, moved, 2, 3))
    rotations = data.rotations(k)
    for j in range(moved):
        dr_du[3 * j : 3 * j + 3, j, 0, :] = -np.eye(3)
        dr_du[3 * j : 3 * j + 3, j, 1, :] = rotations[j]
    gain = -(normal_inv @ jac.T) @ dr_du.reshape(3 * moved + turns, 6 * moved)
    return GyroMatrixFit(
        scale_matrix=k,
        standard_errors=errors,
        bias_dps=bias,
        used=tuple(used),
        residual_deg=data.angles_deg(k),
        residual_identity_deg=data.angles_deg(np.eye(3)),
        unusable=tuple(unusable),
        condition_number=condition,
        directions=np.stack([data.before, data.after], axis=1),
        direction_gain=gain.reshape(3, 3, moved, 2, 3),
        known_turns=tuple(used[i] for i in data.turns),
        known_turn_swept_deg=tuple(float(a) for a in np.degrees(data.swept_rad(k))),
    )
