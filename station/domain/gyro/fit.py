"""Fit the g-sensitivity error model to a rate-table / centrifuge log.

Identifiability first (:mod:`station.domain.gyro.identifiability`), then per gyro axis the
full model (:mod:`station.domain.gyro.model`, bias + S + B + N) by SVD least squares
(:mod:`station.domain.gyro.lsq`) on the excited regressors, then the nested-model comparison
(:mod:`station.domain.gyro.comparison`). A term the log cannot estimate is ``None`` in the
report, with its reason in ``unestimable``; it is never given a number.

The report is a pydantic model: ``to_dict()`` gives the JSON answer of
``calstation gyro fit --json`` and ``GyroFitReport.from_dict()`` reads it back.
"""

from typing import Any

import numpy as np
from pydantic import BaseModel

from station.domain.constants import DEFAULT_ALPHA
from station.domain.errors import InputError
from station.domain.gyro.comparison import AxisComparison, compare_axis
from station.domain.gyro.identifiability import (
    IdentifiabilityReport,
    NotIdentifiableError,
    TermStatus,
    check_identifiability,
    excitation,
)
from station.domain.gyro.log import GyroLog
from station.domain.gyro.lsq import solve
from station.domain.gyro.model import PPM, TERMS_PER_AXIS, GyroErrorModel, regressors, term_names
from station.domain.sensors.sensor import AXES

Vector = list[float | None]
Matrix = list[list[float | None]]
#: The fields of the error model's families of terms, in the order of a gyro's row.
FAMILIES = ("bias_dps", "scale_matrix", "bias_g_sensitivity_dps_per_g", "g_sensitivity_ppm_per_g")


class GyroFitErrors(BaseModel):
    """One-sigma standard errors, same shapes and units as the estimates."""

    bias_dps: Vector
    scale_matrix: Matrix
    bias_g_sensitivity_dps_per_g: Matrix
    g_sensitivity_ppm_per_g: Matrix


class GyroFitReport(BaseModel):
    """Result of fitting a log. Row = gyro axis i (x, y, z), column = axis j."""

    dwells: int
    bias_dps: Vector
    scale_matrix: Matrix
    bias_g_sensitivity_dps_per_g: Matrix
    g_sensitivity_ppm_per_g: Matrix
    sense_axis: list[str | None]
    sense_axis_reason: list[str | None]
    residual_rms_dps: list[float]
    standard_errors: GyroFitErrors
    unestimable: list[TermStatus]
    identifiability: IdentifiabilityReport
    comparison: list[AxisComparison]

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dictionary (the ``--json`` answer)."""
        return self.model_dump(mode="json")

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "GyroFitReport":
        """Read back a :meth:`to_dict` answer (validated)."""
        return cls.model_validate(data)

    def error_model(self) -> GyroErrorModel:
        """The fitted model for compensation; refused when any term was not estimable."""
        if self.unestimable:
            raise NotIdentifiableError(
                "no complete model to compensate with: the log does not determine "
                + ", ".join(t.term for t in self.unestimable)
                + " (reasons in the fit's unestimable list)"
            )
        return GyroErrorModel(
            np.array(self.bias_dps, dtype=np.float64),
            np.array(self.scale_matrix, dtype=np.float64),
            np.array(self.bias_g_sensitivity_dps_per_g, dtype=np.float64),
            np.array(self.g_sensitivity_ppm_per_g, dtype=np.float64) / PPM,
        )


def _split(row: list[float | None]) -> tuple[float | None, Vector, Vector, Vector]:
    n_ppm = [None if v is None else v * PPM for v in row[7:10]]
    return row[0], row[1:4], row[4:7], n_ppm


def _families(rows: list[list[float | None]]) -> dict[str, Any]:
    """The three gyros' rows as the report's families of terms (:data:`FAMILIES`)."""
    columns = zip(*map(_split, rows), strict=True)
    return {name: list(column) for name, column in zip(FAMILIES, columns, strict=True)}


def _sense_axis(
    values: Vector, errors: Vector, comparison: AxisComparison
) -> tuple[str | None, str | None]:
    """Axis of the dominant N term of one gyro, or None with the reason.

    Only when the comparison finds the N terms needed (N given B, or N against the
    plain model when B cannot be fitted); then the largest |N_ij| among the terms that
    differ from zero on their own, or else the one with the largest |N_ij|/σ.
    """
    # Imported here: scipy.special takes ~0.5 s to load, and the results server, which
    # imports this module with the run record, rarely needs it (the server's start-up).
    from scipy import special

    if all(v is None for v in values):
        return None, "no N term is estimable from this log"
    tests = {(t.full, t.reduced): t.p_value for t in comparison.tests}
    p_value = tests.get(("both", "bias"), tests.get(("scale-factor", "none")))
    if p_value is None or p_value >= comparison.alpha:
        return None, f"the N terms are not needed at level {comparison.alpha:g}"
    scored = [
        (abs(v), abs(v) / e, j)
        for j, (v, e) in enumerate(zip(values, errors, strict=True))
        if v is not None and e is not None and e > 0
    ]
    significant = [s for s in scored if 2 * special.ndtr(-s[1]) < comparison.alpha]
    if significant:
        return AXES[max(significant)[2]], None
    return AXES[max(scored, key=lambda s: s[1])[2]], None


def fit_log(log: GyroLog, alpha: float = DEFAULT_ALPHA) -> GyroFitReport:
    """Fit the model to ``log`` (module docstring)."""
    if len(log) < TERMS_PER_AXIS + 1:
        raise InputError(
            f"{len(log)} dwells in the log; fitting {TERMS_PER_AXIS} terms per gyro "
            f"needs at least {TERMS_PER_AXIS + 1}"
        )
    report = check_identifiability(log)
    rows: list[list[float | None]] = []
    error_rows: list[list[float | None]] = []
    rms: list[float] = []
    comparison: list[AxisComparison] = []
    for axis in range(3):
        status = report.axes[axis]
        design = regressors(axis, log.rate, log.acc)
        y = log.gyro[:, axis]
        mask, _, _ = excitation(log, axis)
        columns = np.flatnonzero(mask)
        ls = solve(design[:, columns], y)
        value: list[float | None] = [None] * TERMS_PER_AXIS
        error: list[float | None] = [None] * TERMS_PER_AXIS
        for c, k in enumerate(columns):
            if status.terms[k].estimable:
                value[k] = float(ls.coef[c])
                error[k] = None if np.isnan(ls.stderr[c]) else float(ls.stderr[c])
        rows.append(value)
        error_rows.append(error)
        rms.append(float(np.sqrt(ls.rss / y.size)))
        comparison.append(compare_axis(status, design, y, term_names(axis), alpha))
    values, errors = _families(rows), _families(error_rows)
    n_terms = zip(values[FAMILIES[3]], errors[FAMILIES[3]], comparison, strict=True)
    sense = [_sense_axis(n, e, c) for n, e, c in n_terms]
    return GyroFitReport(
        dwells=len(log),
        **values,
        sense_axis=[s[0] for s in sense],
        sense_axis_reason=[s[1] for s in sense],
        residual_rms_dps=rms,
        standard_errors=GyroFitErrors(**errors),
        unestimable=report.unestimable(),
        identifiability=report,
        comparison=comparison,
    )
