"""Which form of g-sensitivity do the data support? Nested models, per gyro axis.

Four models of gyro i, each fitted by least squares (:mod:`station.domain.gyro.lsq`) on the
terms the log can estimate (:mod:`station.domain.gyro.identifiability`):

    none          b_i + Σ S_ij·ω_j
    bias          none + Σ B_ij·a_j               (deg/s/g, the usual model)
    scale-factor  none + (Σ N_ij·a_j)·ω_i         ([Park2014]_ eq. 4)
    both          none + B + N

Extra-sum-of-squares F-tests, with RSS_r, RSS_f the residual sums of the reduced and
full model, q the extra terms and n − k_f the full model's residual degrees of freedom::

    F = ((RSS_r − RSS_f)/q) / (RSS_f/(n − k_f))

"scale-factor given bias" (both against bias) asks whether N is needed once B is in,
"bias given scale-factor" the converse. AIC = n·ln(RSS/n) + 2k, BIC = n·ln(RSS/n) + k·ln n.
Verdict at level α: "scale-factor" when only N is needed, "bias" when only B,
"both", "none" when neither model beats the plain one, "indistinguishable" when the g
terms are needed but the log cannot say which.
"""

from typing import Final, Literal

import numpy as np
from pydantic import BaseModel

from station.domain.arrays import FloatArray
from station.domain.gyro.identifiability import AxisIdentifiability
from station.domain.gyro.lsq import solve

ModelName = Literal["none", "bias", "scale-factor", "both"]
Verdict = Literal["none", "bias", "scale-factor", "both", "indistinguishable"]
MODELS: Final[tuple[ModelName, ...]] = ("none", "bias", "scale-factor", "both")
_TINY: Final = 1e-300
_F_MAX: Final = 1e300


class NestedModel(BaseModel):
    """One fitted model of the comparison."""

    name: ModelName
    terms: list[str]
    parameters: int
    rss: float
    aic: float
    bic: float


class FTest(BaseModel):
    """Extra-sum-of-squares F-test of a reduced model inside a full one."""

    full: ModelName
    reduced: ModelName
    f: float | None
    df_num: int
    df_den: int
    p_value: float | None
    reason: str | None = None


class AxisComparison(BaseModel):
    """The nested-model comparison of one gyro axis."""

    axis: str
    alpha: float
    models: list[NestedModel]
    tests: list[FTest]
    preferred_by_bic: ModelName | None
    verdict: Verdict | None
    reason: str | None = None


def _term_sets(status: AxisIdentifiability) -> dict[ModelName, list[int]]:
    usable = [k for k, t in enumerate(status.terms) if t.estimable]
    base = [k for k in usable if k < 4]
    b = [k for k in usable if 4 <= k < 7]
    n = [k for k in usable if k >= 7]
    return {
        "none": base,
        "bias": base + b if b else [],
        "scale-factor": base + n if n else [],
        "both": base + b + n if b and n else [],
    }


def _model(
    name: ModelName, columns: list[int], design: FloatArray, y: FloatArray, names: list[str]
) -> NestedModel:
    ls = solve(design[:, columns], y)
    n = y.size
    fit_term = n * np.log(max(ls.rss / n, _TINY))
    return NestedModel(
        name=name,
        terms=[names[k] for k in columns],
        parameters=ls.rank,
        rss=ls.rss,
        aic=float(fit_term + 2 * ls.rank),
        bic=float(fit_term + ls.rank * np.log(n)),
    )


def _f_test(full: NestedModel, reduced: NestedModel, n: int) -> FTest:
    q = full.parameters - reduced.parameters
    df_den = n - full.parameters
    test = FTest(
        full=full.name, reduced=reduced.name, f=None, df_num=q, df_den=df_den, p_value=None
    )
    if q <= 0 or df_den <= 0:
        reason = "no residual degrees of freedom" if df_den <= 0 else "no extra terms"
        return test.model_copy(update={"reason": reason})
    f = ((reduced.rss - full.rss) / q) / (max(full.rss, _TINY) / df_den)
    f = float(min(max(f, 0.0), _F_MAX))
    # Imported here: scipy.special takes ~0.5 s to load, and the results server, which
    # imports this module with the run record, rarely needs it (the server's start-up).
    from scipy import special

    return test.model_copy(update={"f": f, "p_value": float(special.fdtrc(q, df_den, f))})


def _needed(
    tests: dict[tuple[ModelName, ModelName], FTest],
    full: ModelName,
    reduced: ModelName,
    alpha: float,
) -> bool:
    test = tests.get((full, reduced))
    return test is not None and test.p_value is not None and test.p_value < alpha


def compare_axis(
    status: AxisIdentifiability, design: FloatArray, y: FloatArray, names: list[str], alpha: float
) -> AxisComparison:
    """Fit the four nested models of one gyro axis and decide the form (module docstring)."""
    sets = _term_sets(status)
    models = {name: _model(name, sets[name], design, y, names) for name in MODELS if sets[name]}
    pairs: list[tuple[ModelName, ModelName]] = [
        ("bias", "none"),
        ("scale-factor", "none"),
        ("both", "bias"),
        ("both", "scale-factor"),
    ]
    tests = {
        (full, reduced): _f_test(models[full], models[reduced], y.size)
        for full, reduced in pairs
        if full in models and reduced in models
    }
    preferred = min(models.values(), key=lambda m: m.bic).name if models else None
    verdict: Verdict | None = None
    reason = None
    if "both" not in models or not status.form_question:
        reason = status.form_reason or "the bias and scale-factor forms cannot both be fitted"
    elif tests[("both", "bias")].p_value is None:
        reason = tests[("both", "bias")].reason
    else:
        need_n = _needed(tests, "both", "bias", alpha)
        need_b = _needed(tests, "both", "scale-factor", alpha)
        if need_n and need_b:
            verdict = "both"
        elif need_n:
            verdict = "scale-factor"
        elif need_b:
            verdict = "bias"
        elif _needed(tests, "bias", "none", alpha) or _needed(tests, "scale-factor", "none", alpha):
            verdict = "indistinguishable"
        else:
            verdict = "none"
    return AxisComparison(
        axis=status.axis,
        alpha=alpha,
        models=list(models.values()),
        tests=list(tests.values()),
        preferred_by_bic=preferred,
        verdict=verdict,
        reason=reason,
    )
