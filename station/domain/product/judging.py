"""A run's limit checks on its measured values, and the failure list of its verdict.

One place for judging, used by the station at a run's verdict
(:mod:`station.run.verdict`) and by the end-of-line report to
re-judge stored runs against a candidate limits profile (:func:`rejudge`, the report's
what-if). Each value is compared with the profile by :func:`station.domain.product.limits.check`, in
a
fixed order: every pose's noise per axis and link loss, the offsets, the sensitivities,
the verification pose's error, the gyro biases, the gyro matrix K's scale errors and
misalignments. A verdict's failures are those found while the run went (in the order
found), then the checks' failures not among them; a run passes without failures.

Each value that carries an expanded uncertainty U (the coefficients, the verification
error, K's entries: :data:`GUARDED_CHECKS`) is judged by the profile's decision rule with
it; the others by simple acceptance. :func:`check_rules` says which rule judged each
limit, as the run's record keeps it.
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace

from station.domain.product.limits import CHECKS, LimitsProfile, check
from station.domain.record.records import DecisionRule, FailureReason
from station.domain.sensors.sensor import AXES, Axis

Triple = tuple[float, float, float]
Matrix = tuple[Triple, Triple, Triple]

#: Each check whose value carries an expanded uncertainty U, and the key of
#: :attr:`Measured.uncertainty` that holds it: the checks a ``guarded`` rule judges with U.
GUARDED_CHECKS: dict[str, str] = {
    "offset": "offset",
    "sensitivity": "sensitivity",
    "verification_error": "verification_error",
    "gyro_bias": "gyro_bias",
    "gyro_scale": "gyro_matrix",
    "gyro_misalignment": "gyro_matrix",
}

#: The checks :func:`rejudge` takes again from a stored run's values. Link loss is
#: stored only when it failed (its value in the failure), so a stored run is re-judged
#: on the losses that failed; the failures found while the run went (saturation, the
#: solve, write-back, the unit's output, an abort) stay as the station found them.
REJUDGED = ("pose_noise", "link_loss", "offset", "sensitivity", "verification_error", "gyro_bias")


@dataclass(frozen=True)
class Measured:
    """What a run measured that the limits judge.

    ``pose_noise``: per pose index, the standard deviation of its samples per axis
    (counts); ``link_loss``: per pose index, the fraction of samples lost; ``offset``,
    ``sensitivity``: the solved coefficients; ``verification``: the verification pose's
    index and its error (mg); ``gyro_bias``: deg/s; ``gyro_matrix``: K (row = gyro);
    ``uncertainty``: the expanded uncertainty U of each axis' ``offset``, ``sensitivity``
    and ``gyro_bias`` (keys as the fields', three values), of the ``verification_error``
    (one, mg) and of K's ``gyro_matrix`` entries (nine, row by row), which a profile's
    guarded decision rule judges with.
    """

    pose_noise: Mapping[int, Triple] = field(default_factory=dict)
    link_loss: Mapping[int, float] = field(default_factory=dict)
    offset: Triple | None = None
    sensitivity: Triple | None = None
    verification: tuple[int, float] | None = None
    gyro_bias: Triple | None = None
    gyro_matrix: Matrix | None = None
    uncertainty: Mapping[str, tuple[float, ...]] = field(default_factory=dict)


def limit_checks(profile: LimitsProfile, measured: Measured) -> list[FailureReason]:
    """The failed checks of ``measured`` against ``profile``, in the checks' order."""
    reasons: list[FailureReason | None] = []
    for i in sorted({*measured.pose_noise, *measured.link_loss}):
        for axis, std in zip(AXES, measured.pose_noise.get(i, ()), strict=False):
            reasons.append(check(profile, "pose_noise", std, axis=axis, pose=i))
        if i in measured.link_loss:
            reasons.append(check(profile, "link_loss", measured.link_loss[i], pose=i))

    def guarded(
        code: str, value: float, index: int, axis: Axis | None = None, pose: int | None = None
    ) -> FailureReason | None:
        """The check of a value that may carry its U: entry ``index`` of its U's key."""
        family = measured.uncertainty.get(GUARDED_CHECKS[code])
        uncertainty = None if family is None else family[index]
        return check(profile, code, value, axis=axis, pose=pose, uncertainty=uncertainty)

    for code, values in (("offset", measured.offset), ("sensitivity", measured.sensitivity)):
        for i, (axis, value) in enumerate(zip(AXES, values or (), strict=False)):
            reasons.append(guarded(code, value, i, axis))
    if measured.verification is not None:
        pose, error = measured.verification
        reasons.append(guarded("verification_error", error, 0, pose=pose))
    for i, (axis, bias) in enumerate(zip(AXES, measured.gyro_bias or (), strict=False)):
        reasons.append(guarded("gyro_bias", bias, i, axis))
    k = measured.gyro_matrix
    if k is not None:
        reasons += [guarded("gyro_scale", k[i][i] - 1.0, 4 * i, AXES[i]) for i in range(3)]
        for i, j in ((i, j) for i in range(3) for j in range(3) if i != j):
            reasons.append(guarded("gyro_misalignment", k[i][j], 3 * i + j, AXES[i]))
    return [r for r in reasons if r is not None]


def check_rules(profile: LimitsProfile, measured: Measured) -> dict[str, DecisionRule]:
    """The decision rule that judges each limit ``profile`` sets (by check code): the
    profile's where the value carries its U in ``measured`` (:data:`GUARDED_CHECKS`),
    simple acceptance elsewhere (a value without U is judged by itself)."""
    return {
        code: profile.rule if GUARDED_CHECKS.get(code) in measured.uncertainty else "simple"
        for code, name in CHECKS.items()
        if getattr(profile, name) is not None
    }


def uncertainty_of(
    offset: Triple | None,
    sensitivity: Triple | None,
    gyro_bias: Triple | None,
    verification_error: float | None = None,
    gyro_matrix: Matrix | None = None,
) -> dict[str, tuple[float, ...]]:
    """:attr:`Measured.uncertainty` from the U of each coefficient family, of the
    verification error and of K (None: unknown)."""
    entries = None if gyro_matrix is None else tuple(v for row in gyro_matrix for v in row)
    families: dict[str, tuple[float, ...] | None] = {
        "offset": offset,
        "sensitivity": sensitivity,
        "gyro_bias": gyro_bias,
        "verification_error": None if verification_error is None else (verification_error,),
        "gyro_matrix": entries,
    }
    return {code: values for code, values in families.items() if values is not None}


def verdict_failures(
    found: Sequence[FailureReason], checked: Sequence[FailureReason]
) -> list[FailureReason]:
    """A verdict's failures: those ``found`` while the run went, then the ``checked``
    ones not among them."""
    return [*found, *(f for f in checked if f not in found)]


def rejudge(
    stored: Sequence[FailureReason], profile: LimitsProfile, measured: Measured
) -> list[FailureReason]:
    """The failures a stored run would have had under ``profile``.

    The failures found while the run went are kept; the limit checks are taken again
    on ``measured`` (its link losses: those ``stored`` failed on). An aborted run was
    never checked and stays as it is.
    """
    if any(f.code == "aborted" for f in stored):
        return list(stored)
    losses = {
        f.pose: f.measured
        for f in stored
        if f.code == "link_loss" and f.pose is not None and f.measured is not None
    }
    measured = replace(measured, link_loss={**measured.link_loss, **losses})
    again = (*REJUDGED, *(("gyro_scale", "gyro_misalignment") if measured.gyro_matrix else ()))
    found = [f for f in stored if f.code not in again]
    return verdict_failures(found, limit_checks(profile, measured))
