"""The report's parameters and the limits their capability is measured against.

What a parameter is (its name, limits family and unit), not where it is stored: the
columns that hold each one are :mod:`db.rollups`' business. Each parameter belongs to a
limits family (``offset``, ``sensitivity``, ``verification_error``, ``pose_noise``,
``gyro_bias``: the check codes of a limits profile, :data:`station.domain.product.limits.CHECKS`).
:func:`profile_bounds` is the one place bounds enter the report: from a limits profile
(:mod:`station.domain.product.limits`).
"""

from dataclasses import dataclass

from station.domain.product.limits import CHECKS, LimitsProfile

#: Limits family → ``(lower, upper)`` of the profile's :class:`station.domain.product.limits.Bounds`
#: (``None`` for an unbounded side): the plain pair the database stores and compares.
FamilyBounds = dict[str, tuple[float | None, float | None]]

#: The limits families the report measures capability against.
FAMILIES = ("offset", "sensitivity", "verification_error", "pose_noise", "gyro_bias")


def profile_bounds(profile: LimitsProfile) -> FamilyBounds:
    """The bounds of ``profile`` per limits family (counts, counts/g, mg, counts, deg/s)."""
    bounds = {family: getattr(profile, CHECKS[family]) for family in FAMILIES}
    return {family: (b.lower, b.upper) for family, b in bounds.items()}


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
