"""The report's parameters and the limits their capability is measured against.

What a parameter is (its name, limits family and unit), not where it is stored: the
columns that hold each one are :mod:`db.rollups`' business. Each parameter belongs to a
limits family (``offset``, ``sensitivity``, ``verification_error``, ``pose_noise``,
``gyro_bias``: the check codes of a limits profile, :data:`station.limits.CHECKS`).
:func:`profile_bounds` is the one place bounds enter the report: from a limits profile
(:mod:`station.limits`).
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from station.limits import CHECKS, DEFAULT_PROFILE, LimitsProfile, load_profile
from station.records import LimitsRef

#: Limits family → ``(lower, upper)`` of the profile's :class:`station.limits.Bounds`
#: (``None`` for an unbounded side): the plain pair the database stores and compares.
FamilyBounds = dict[str, tuple[float | None, float | None]]

#: The limits families the report measures capability against.
FAMILIES = ("offset", "sensitivity", "verification_error", "pose_noise", "gyro_bias")


def profile_bounds(profile: LimitsProfile) -> FamilyBounds:
    """The bounds of ``profile`` per limits family (counts, counts/g, mg, counts, deg/s)."""
    bounds = {family: getattr(profile, CHECKS[family]) for family in FAMILIES}
    return {family: (b.lower, b.upper) for family, b in bounds.items()}


def default_bounds() -> FamilyBounds:
    """The bounds of the shipped default profile (datasheet figures of the KXM52-1050)."""
    return profile_bounds(load_profile())


def choose_profile(
    used: Sequence[LimitsRef], known: Mapping[str, LimitsProfile]
) -> tuple[LimitsProfile, str]:
    """The profile capability is measured against, and a line saying why that one.

    The profile every run in range was judged by when it is in ``known`` with the same
    hash; otherwise the default profile (or the first one known).
    """
    if len(used) == 1:
        ref = used[0]
        profile = known.get(ref.name)
        if profile is not None and profile.sha256 == ref.sha256:
            return profile, f"limits profile {ref.name} v{ref.version}, as every run in range"
    default = known.get(DEFAULT_PROFILE) or next(iter(known.values()))
    if not used:
        why = "no run in range"
    elif len(used) > 1:
        why = f"the runs in range were judged by {len(used)} profiles"
    else:
        why = f"the runs' profile {used[0].name} v{used[0].version} is not in the limits file"
    return default, f"limits profile {default.name} v{default.version} ({why})"


@dataclass(frozen=True)
class ParameterSpec:
    """One reported parameter: its name, limits family and unit."""

    name: str
    family: str
    unit: str


PARAMETERS: tuple[ParameterSpec, ...] = (
    *(ParameterSpec(f"offset_{a}", "offset", "counts") for a in "xyz"),
    *(ParameterSpec(f"sensitivity_{a}", "sensitivity", "counts/g") for a in "xyz"),
    ParameterSpec("verification_error", "verification_error", "mg"),
    *(ParameterSpec(f"pose_noise_{a}", "pose_noise", "counts") for a in "xyz"),
    *(ParameterSpec(f"gyro_bias_{a}", "gyro_bias", "deg/s") for a in "xyz"),
)

#: The calibration coefficients, each with an individuals (I-MR) control chart.
COEFFICIENTS: tuple[str, ...] = tuple(
    f"{kind}_{a}" for kind in ("offset", "sensitivity") for a in "xyz"
)
