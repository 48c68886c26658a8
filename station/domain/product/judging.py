"""A run's limit checks on its measured values, and the failure list of its verdict.

One place for judging, used by the station at a run's verdict
(:mod:`station.run.verdict`) and by the end-of-line report to
re-judge stored runs against a candidate limits profile (:func:`rejudge`, the report's
what-if). Each value is compared with the profile by :func:`station.domain.product.limits.check`, in
a
fixed order: every pose's noise per axis and link loss, the offsets, the sensitivities,
the verification pose's error, the gyro biases. A verdict's failures are those found
while the run went (in the order found), then the checks' failures not among them; a
run passes without failures.
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

from station.domain.product.limits import LimitsProfile, check
from station.domain.record.records import FailureReason
from station.domain.sensors.sensor import AXES

Triple = tuple[float, float, float]

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
    index and its error (mg); ``gyro_bias``: deg/s; ``uncertainty``: the expanded
    uncertainty U of each axis' ``offset``, ``sensitivity`` and ``gyro_bias`` (keys as the
    fields'), which a profile's guarded decision rule judges with.
    """

    pose_noise: Mapping[int, Triple] = field(default_factory=dict)
    link_loss: Mapping[int, float] = field(default_factory=dict)
    offset: Triple | None = None
    sensitivity: Triple | None = None
    verification: tuple[int, float] | None = None
    gyro_bias: Triple | None = None
    uncertainty: Mapping[str, Triple] = field(default_factory=dict)


def limit_checks(profile: LimitsProfile, measured: Measured) -> list[FailureReason]:
    """The failed checks of ``measured`` against ``profile``, in the checks' order."""
    reasons: list[FailureReason | None] = []
    for i in sorted({*measured.pose_noise, *measured.link_loss}):
        for axis, std in zip(AXES, measured.pose_noise.get(i, ()), strict=False):
            reasons.append(check(profile, "pose_noise", std, axis=axis, pose=i))
        if i in measured.link_loss:
            reasons.append(check(profile, "link_loss", measured.link_loss[i], pose=i))
    u = measured.uncertainty
    for code, values in (("offset", measured.offset), ("sensitivity", measured.sensitivity)):
        for i, (axis, value) in enumerate(zip(AXES, values or (), strict=False)):
            reasons.append(check(profile, code, value, axis=axis, uncertainty=_u(u, code, i)))
    if measured.verification is not None:
        pose, error = measured.verification
        reasons.append(check(profile, "verification_error", error, pose=pose))
    for i, (axis, bias) in enumerate(zip(AXES, measured.gyro_bias or (), strict=False)):
        reasons.append(
            check(profile, "gyro_bias", bias, axis=axis, uncertainty=_u(u, "gyro_bias", i))
        )
    return [r for r in reasons if r is not None]


def _u(uncertainty: Mapping[str, Triple], code: str, axis: int) -> float | None:
    values = uncertainty.get(code)
    return None if values is None else values[axis]


def uncertainty_of(
    offset: Triple | None, sensitivity: Triple | None, gyro_bias: Triple | None
) -> dict[str, Triple]:
    """:attr:`Measured.uncertainty` from the U of each coefficient family (None: unknown)."""
    families = (("offset", offset), ("sensitivity", sensitivity), ("gyro_bias", gyro_bias))
    return {code: values for code, values in families if values is not None}


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
    measured = Measured(
        pose_noise=measured.pose_noise,
        link_loss={**measured.link_loss, **losses},
        offset=measured.offset,
        sensitivity=measured.sensitivity,
        verification=measured.verification,
        gyro_bias=measured.gyro_bias,
        uncertainty=measured.uncertainty,
    )
    found = [f for f in stored if f.code not in REJUDGED]
    return verdict_failures(found, limit_checks(profile, measured))
