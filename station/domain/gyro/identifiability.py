"""Can this log separate the terms of the error model? Checked before any fit.

Three rules, per gyro axis i, on the regressors of :func:`station.domain.gyro.model.regressors`:

1. Excitation. ``S_ij`` needs rate about j (|ω_j| ≥ 1 deg/s somewhere). ``B_ij`` needs
   the acceleration along j to vary (spread ≥ 0.1 g): a constant acceleration is a
   bias. ``N_ij`` needs rate about i *and* the acceleration along j to vary while that
   rate is applied (spread weighted by ω_i² ≥ 0.1 g): with gravity one way only along
   the input axis, ``N_ii`` is a scale-factor error. A term dropped here while its
   acceleration has a non-zero mean leaves a caveat: that mean times the term is
   absorbed by the bias (or by ``S_ii``).
2. Collinearity. The excited columns, each scaled to unit norm, are decomposed by SVD;
   directions with singular value below ``RCOND`` times the largest are the (near)
   null space. A term whose unit vector has a component of more than ``NULL_WEIGHT``
   in that space cannot be estimated; the terms sharing the null space with it are
   named as the confounders.
3. The form question (bias form ``B`` against scale-factor form ``N``). The g-terms
   must also be separable from a scale-factor non-linearity of the gyro itself
   (columns ω_i² and ω_i³): on a single centrifuge mount a = ω²r, so ``B·a`` is a
   quadratic and ``N·a·ω`` a cubic in the rate, and the log cannot tell g-sensitivity
   from non-linearity. Flipping the mount (acceleration both ways at the same rate)
   and both spin directions separate them.

A gyro axis can answer the form question when, for some acceleration axis j, both
``B_ij`` and ``N_ij`` are estimable.
"""

from typing import Final

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel

from station.domain.arrays import FloatArray
from station.domain.errors import CalstationError, InputError
from station.domain.gyro.log import GyroLog
from station.domain.gyro.model import TERMS_PER_AXIS, regressors, term_names
from station.domain.sensors.sensor import AXES

RATE_FLOOR_DPS: Final = 1.0
ACC_SPREAD_FLOOR_G: Final = 0.1
RCOND: Final = 1e-3
NULL_WEIGHT: Final = 0.05
_NONLINEARITY = ("scale-factor non-linearity ω²", "scale-factor non-linearity ω³")


class NotIdentifiableError(CalstationError):
    """The log cannot separate the terms a question needs."""


class TermStatus(BaseModel):
    """Whether one term can be estimated from the log, and why not."""

    term: str
    estimable: bool
    reason: str | None = None


class AxisIdentifiability(BaseModel):
    """Findings for one gyro axis."""

    axis: str
    dwells: int
    excited_columns: int
    rank: int
    condition_number: float | None
    terms: list[TermStatus]
    caveats: list[str]
    form_question: bool
    form_reason: str | None = None


class IdentifiabilityReport(BaseModel):
    """Findings for the three gyro axes, x, y, z."""

    axes: list[AxisIdentifiability]

    def status(self, term: str) -> TermStatus:
        """The status of ``term`` (e.g. ``"N_xy"``)."""
        found = next((s for axis in self.axes for s in axis.terms if s.term == term), None)
        if found is None:
            raise KeyError(term)
        return found

    def unestimable(self) -> list[TermStatus]:
        """Every term that cannot be estimated, in axis and column order."""
        return [s for axis in self.axes for s in axis.terms if not s.estimable]

    def require_form_question(self) -> None:
        """Raise :class:`NotIdentifiableError` unless every axis can answer the form question."""
        refused = [f"gyro {a.axis}: {a.form_reason}" for a in self.axes if not a.form_question]
        if refused:
            raise NotIdentifiableError(
                "the log cannot tell bias-form from scale-factor-form g-sensitivity: "
                + "; ".join(refused)
            )


def excitation(log: GyroLog, axis: int) -> tuple[NDArray[np.bool_], dict[str, str], list[str]]:
    """Rule 1: mask of excited columns of gyro ``axis``, reasons for the others, caveats."""
    names = term_names(axis)
    a_i = AXES[axis]
    reasons: dict[str, str] = {}
    caveats: list[str] = []
    rate_max = np.max(np.abs(log.rate), axis=0) if len(log) else np.zeros(3)
    for j, a_j in enumerate(AXES):
        if rate_max[j] < RATE_FLOOR_DPS:
            reasons[names[1 + j]] = (
                f"no rate about {a_j} in the log (|rate_ref_{a_j}| < {RATE_FLOOR_DPS:g} deg/s)"
            )
        mean, spread = float(np.mean(log.acc[:, j])), float(np.std(log.acc[:, j]))
        if spread < ACC_SPREAD_FLOOR_G:
            reasons[names[4 + j]] = (
                f"acceleration along {a_j} does not vary in the log "
                f"(spread {spread:.3f} g < {ACC_SPREAD_FLOOR_G:g} g)"
            )
            if abs(mean) >= ACC_SPREAD_FLOOR_G:
                caveats.append(f"bias_{a_i} includes {names[4 + j]} × {mean:+.2f} g")
        n_term = names[7 + j]
        if rate_max[axis] < RATE_FLOOR_DPS:
            reasons[n_term] = f"no rate about {a_i} (the input axis) in the log"
            continue
        weights = log.rate[:, axis] ** 2
        w_mean = float(np.average(log.acc[:, j], weights=weights))
        w_spread = float(np.sqrt(np.average((log.acc[:, j] - w_mean) ** 2, weights=weights)))
        if w_spread < ACC_SPREAD_FLOOR_G:
            reasons[n_term] = (
                f"acceleration along {a_j} does not vary while rate about {a_i} is applied "
                f"(spread {w_spread:.3f} g < {ACC_SPREAD_FLOOR_G:g} g; it needs both signs)"
            )
            if abs(w_mean) >= ACC_SPREAD_FLOOR_G:
                caveats.append(f"S_{a_i}{a_i} includes {n_term} × {w_mean:+.2f} g")
    mask = np.array([name not in reasons for name in names])
    return mask, reasons, caveats


def normalised(columns: FloatArray) -> FloatArray:
    """Columns scaled to unit Euclidean norm (zero columns left as they are)."""
    norms = np.linalg.norm(columns, axis=0)
    return columns / np.where(norms > 0, norms, 1.0)


def _null_space(z: FloatArray) -> tuple[FloatArray, int, float | None]:
    """Near-null space (columns), rank and condition number of ``z`` (unit-norm columns)."""
    if z.shape[1] == 0:
        return np.zeros((0, 0)), 0, None
    _, s, vt = np.linalg.svd(z, full_matrices=True)
    s_full = np.zeros(z.shape[1])
    s_full[: s.size] = s
    keep = s_full > RCOND * s_full[0]
    rank = int(np.count_nonzero(keep))
    condition = float(s_full[0] / s_full[rank - 1]) if rank == z.shape[1] else None
    return vt[~keep].T, rank, condition


def _confounded(null: FloatArray, names: list[str], k: int) -> list[str] | None:
    """Partners of column ``k`` in the null space, or None when ``k`` is estimable."""
    if null.shape[1] == 0:
        return None
    projection = null @ null[k]
    if abs(projection[k]) ** 0.5 <= NULL_WEIGHT:
        return None
    scale = np.max(np.abs(projection))
    return [names[m] for m in range(len(names)) if m != k and abs(projection[m]) > 0.01 * scale]


def _axis(log: GyroLog, axis: int) -> AxisIdentifiability:
    names = term_names(axis)
    a_i = AXES[axis]
    mask, reasons, caveats = excitation(log, axis)
    design = regressors(axis, log.rate, log.acc)
    columns = [k for k in range(TERMS_PER_AXIS) if mask[k]]
    col_names = [names[k] for k in columns]
    null, rank, condition = _null_space(normalised(design[:, columns]))
    for c, k in enumerate(columns):
        partners = _confounded(null, col_names, c)
        if partners is not None:
            reasons[names[k]] = (
                f"confounded with {', '.join(partners)} in this log"
                if partners
                else "its regressor is (nearly) zero in this log"
            )
    # Rule 3: the g-terms against a scale-factor non-linearity of the gyro itself.
    if mask[1 + axis]:
        w = log.rate[:, axis]
        extended = np.column_stack([design[:, columns], w**2, w**3])
        ext_names = [*col_names, *_NONLINEARITY]
        ext_null, _, _ = _null_space(normalised(extended))
        for c, k in enumerate(columns):
            if k < 4 or names[k] in reasons:
                continue
            partners = _confounded(ext_null, ext_names, c)
            if partners is not None and any(p in _NONLINEARITY for p in partners):
                reasons[names[k]] = (
                    f"confounded with {', '.join(partners)} of gyro {a_i}: the acceleration "
                    "follows the rate (as on a single centrifuge mount, where a = ω²r); "
                    "flip the mount and spin both ways"
                )
    terms = [TermStatus(term=n, estimable=n not in reasons, reason=reasons.get(n)) for n in names]
    pairs = [j for j in range(3) if terms[4 + j].estimable and terms[7 + j].estimable]
    form_reason = None
    if not pairs:
        missing = ", ".join(t.term for t in terms[4:] if not t.estimable)
        form_reason = (
            f"no acceleration axis j with both B_{a_i}j and N_{a_i}j estimable "
            f"(not estimable: {missing})"
        )
    return AxisIdentifiability(
        axis=a_i,
        dwells=len(log),
        excited_columns=len(columns),
        rank=rank,
        condition_number=condition,
        terms=terms,
        caveats=caveats,
        form_question=bool(pairs),
        form_reason=form_reason,
    )


def check_identifiability(log: GyroLog) -> IdentifiabilityReport:
    """Run the three rules (module docstring) on every gyro axis of ``log``."""
    if len(log) == 0:
        raise InputError("the log holds no dwells")
    return IdentifiabilityReport(axes=[_axis(log, axis) for axis in range(3)])
