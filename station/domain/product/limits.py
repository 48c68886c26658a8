"""Limits profiles: named, versioned pass/fail bounds, read from TOML.

A profile file holds one table per profile (``[profiles.NAME]``, see the shipped
``station/domain/profiles/limits.toml``). Each stored run carries its profile's name,
version and SHA-256; the hash covers the profile's canonical JSON, so a change of any
bound changes it while comments and layout do not.

A check compares one measured value with one pair of bounds and, when it is outside,
returns a typed :class:`station.domain.record.records.FailureReason` (code, measured value, bounds,
axis or pose) rather than free text.
"""

import math
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Self

from pydantic import (
    AfterValidator,
    BaseModel,
    ConfigDict,
    Field,
    JsonValue,
    ValidationError,
    model_validator,
)

from station.domain.errors import InputError
from station.domain.record.records import (
    GYRO_MATRIX_MAX,
    DecisionRule,
    FailureReason,
    LimitsRef,
    document_sha256,
)
from station.domain.record.unit_state import DEFAULT_RETEST_LIMIT
from station.domain.sensors.record_bounds import (
    ADC_SPAN,
    ERROR_MAX_MG,
    GYRO_RANGE_DPS,
    OFFSET_MAX_COUNTS,
    OFFSET_MIN_COUNTS,
    SENSITIVITY_MAX_COUNTS_PER_G,
    Text,
)
from station.domain.sensors.sensor import Axis
from station.domain.toml_text import parse_toml, read_text, shipped_text

DEFAULT_PROFILE = "kxm52-production"


class Bounds(BaseModel):
    """Closed interval [lower, upper]; a missing side is unbounded."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    lower: float | None = None
    upper: float | None = None

    @model_validator(mode="after")
    def _ordered(self) -> Self:
        if self.lower is None and self.upper is None:
            raise ValueError("give lower, upper or both")
        if self.lower is not None and self.upper is not None and self.lower > self.upper:
            raise ValueError(f"lower {self.lower} is above upper {self.upper}")
        return self

    @property
    def sides(self) -> tuple[float, float]:
        """``(lower, upper)`` with a missing side at ∓∞."""
        low = self.lower if self.lower is not None else -math.inf
        return low, self.upper if self.upper is not None else math.inf

    def contains(self, value: float) -> bool:
        """Whether ``value`` lies within the bounds (a NaN or an infinity never does: a
        measurement is finite, and an open side is not a licence for ±∞)."""
        low, high = self.sides
        return math.isfinite(value) and low <= value <= high

    def guarded(self, value: float, u: float) -> bool:
        """Whether ``value ± u`` lies within the bounds: guarded acceptance with a guard
        band w = u on each side (ILAC-G8:09/2019 4.2.2, JCGM 106:2012 8.3.3)."""
        low, high = self.sides
        return math.isfinite(value) and low + u <= value <= high - u

    def describe(self) -> str:
        """``[a, b]``, ``≤ b`` or ``≥ a``."""
        if self.lower is None:
            return f"≤ {self.upper:g}"
        if self.upper is None:
            return f"≥ {self.lower:g}"
        return f"[{self.lower:g}, {self.upper:g}]"


def _plausible(low: float, high: float, what: str, unit: str = "") -> Callable[[Bounds], Bounds]:
    """A check that each side of a profile's bounds lies within ``low…high`` (``unit``),
    the values the checked quantity can take (``what``), naming the side that does not."""

    def check(bounds: Bounds) -> Bounds:
        for side, value in (("lower", bounds.lower), ("upper", bounds.upper)):
            if value is not None and not low <= value <= high:
                raise ValueError(f"{side} {value:g} outside {what} {low:g}…{high:g}{unit}")
        return bounds

    return check


OffsetBounds = Annotated[
    Bounds,
    AfterValidator(
        _plausible(OFFSET_MIN_COUNTS, OFFSET_MAX_COUNTS, "a zero-g output's range", " counts")
    ),
]
"""Zero-g output, counts: one ADC span beyond either rail (−65535…131070)."""
SensitivityBounds = Annotated[
    Bounds,
    AfterValidator(
        _plausible(0, SENSITIVITY_MAX_COUNTS_PER_G, "a sensitivity's range", " counts/g")
    ),
]
"""Sensitivity, counts/g: 0…65535 (more could not show ±1 g inside the ADC)."""
ErrorBounds = Annotated[
    Bounds, AfterValidator(_plausible(0, ERROR_MAX_MG, "an error's range", " mg"))
]
"""An error, mg: 0…1e9 (the largest a record may hold)."""
NoiseBounds = Annotated[Bounds, AfterValidator(_plausible(0, ADC_SPAN, "the ADC span", " counts"))]
"""A spread or residual of ADC readings, counts: 0…65535 (the widest ADC's span)."""
GyroBiasBounds = Annotated[
    Bounds, AfterValidator(_plausible(-GYRO_RANGE_DPS, GYRO_RANGE_DPS, "the gyro range", " deg/s"))
]
"""A gyro bias, deg/s: ±655.36 (the protocol's rate field)."""
FractionBounds = Annotated[Bounds, AfterValidator(_plausible(0, 1, "a fraction's range"))]
"""A fraction (samples lost; a read-back's relative error, past 100 % no read-back): 0…1."""
GyroScaleBounds = Annotated[
    Bounds,
    AfterValidator(
        _plausible(-GYRO_MATRIX_MAX - 1, GYRO_MATRIX_MAX - 1, "the range of a stored K_ii − 1")
    ),
]
"""K_ii − 1 of the gyro matrix: −3…1 (a stored K's entries lie within ±2)."""
GyroMatrixBounds = Annotated[
    Bounds,
    AfterValidator(_plausible(-GYRO_MATRIX_MAX, GYRO_MATRIX_MAX, "the range of a stored K_ij")),
]
"""K_ij of the gyro matrix: ±2."""
AngleBounds = Annotated[Bounds, AfterValidator(_plausible(0, 180, "an angle's range", "°"))]
"""An angle between two directions, degrees: 0…180."""

Name = Annotated[str, Field(pattern=r"^[A-Za-z0-9][A-Za-z0-9._:@\-]{0,63}$")]


class LimitsProfile(BaseModel):
    """The bounds one run is judged against.

    Each bound lies within the values its quantity can take (``OffsetBounds`` and the
    others above), from the hardware, as a run record's numbers do
    (:mod:`station.domain.sensors.record_bounds`): counts within one ADC span beyond either rail,
    spreads within the span, gyro rates within the protocol's field, fractions within
    0…1, angles within 0…180°. A bound outside them checks nothing a bound at their edge
    would not, and a huge finite one (1e300 counts) overflows the report's sums of
    squares and capability; so a profile holding one is refused wherever it comes from:
    a limits file, an uploaded what-if file (:func:`parse_profiles`) or a run's
    submission (:func:`profile_of`), with the field and the range it must lie in.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    name: Name
    version: Name
    description: Text = ""
    offset_counts: OffsetBounds
    sensitivity_counts_per_g: SensitivityBounds
    verification_error_mg: ErrorBounds
    pose_noise_counts: NoiseBounds
    gyro_bias_dps: GyroBiasBounds
    link_loss: FractionBounds
    writeback_relative_error: FractionBounds
    retest_limit: Annotated[
        int | None,
        Field(ge=1, le=100, description="attempts per unit (aborts not counted) before rework"),
    ] = None
    gyro_scale_error: Annotated[
        GyroScaleBounds | None,
        Field(description="K_ii − 1 of the fitted gyro matrix; absent: unchecked"),
    ] = None
    gyro_misalignment: Annotated[
        GyroMatrixBounds | None,
        Field(description="K_ij (i ≠ j) of the gyro matrix; absent: unchecked"),
    ] = None
    gyro_verification_deg: Annotated[
        AngleBounds | None,
        Field(
            description="angle between the gravity change and the rotation the unit's own "
            "calibrated gyros integrate over the verification move, degrees; absent: unchecked"
        ),
    ] = None
    decision_rule: Annotated[
        DecisionRule | None,
        Field(
            description="how a coefficient and its expanded uncertainty U are judged: simple "
            "acceptance (the value within the limits; the default) or guarded acceptance with "
            "a guard band w = U (the value ± U within the limits), ILAC-G8:09/2019"
        ),
    ] = None
    fit_residual_counts: Annotated[
        NoiseBounds | None,
        Field(
            description="largest |studentised residual| of a least-squares fit's poses, counts; "
            "left out, the model's default (station.domain.calibration.consistency)"
        ),
    ] = None

    @property
    def max_residual_counts(self) -> float | None:
        """The fit's residual limit, counts (``None``: the calibration's default)."""
        return None if self.fit_residual_counts is None else self.fit_residual_counts.upper

    @property
    def rule(self) -> DecisionRule:
        """The decision rule the profile judges by (``simple`` when it names none)."""
        return self.decision_rule or "simple"

    @property
    def attempts_allowed(self) -> int:
        """The retest limit, or the default one (:mod:`station.domain.record.unit_state`)."""
        return self.retest_limit if self.retest_limit is not None else DEFAULT_RETEST_LIMIT

    @property
    def document(self) -> dict[str, JsonValue]:
        """The profile as the JSON document its SHA-256 is taken over (and a run carries).

        An optional setting left out (a retest limit, a fit residual limit, the gyro
        bounds) is left out of the document too, so a profile without it hashes as before
        the setting existed.
        """
        unset = {name for name in _OPTIONAL if getattr(self, name) is None}
        return self.model_dump(mode="json", exclude=unset or None)

    @property
    def sha256(self) -> str:
        """SHA-256 of the profile's canonical JSON (sorted keys, no whitespace)."""
        return document_sha256(self.document)

    @property
    def ref(self) -> LimitsRef:
        """What a stored run records of its profile: the reference and the profile itself."""
        document = self.document
        return LimitsRef(
            name=self.name, version=self.version, sha256=document_sha256(document), profile=document
        )


#: Settings a profile may leave out (added after profiles were first stored); absent,
#: they are not part of its hash.
_OPTIONAL = (
    "retest_limit",
    "decision_rule",
    "fit_residual_counts",
    "gyro_scale_error",
    "gyro_misalignment",
    "gyro_verification_deg",
)


def profile_of(ref: LimitsRef) -> LimitsProfile | None:
    """The profile a run's reference carries (``None`` when it carries only the reference).

    :class:`InputError` when the document, though it hashes to the reference, is not a
    limits profile as this software writes it (one that would hash otherwise).
    """
    if ref.profile is None:
        return None
    try:
        profile = LimitsProfile.model_validate(ref.profile)
    except ValidationError as exc:
        first = exc.errors()[0]
        field = ".".join(str(p) for p in first["loc"])
        raise InputError(f"limits.profile: {field}: {first['msg']}") from None
    if profile.sha256 != ref.sha256:
        raise InputError("limits.profile is not a profile's canonical document")
    return profile


#: Check codes: one per kind of bound, each with the profile field it reads.
CHECKS: dict[str, str] = {
    "offset": "offset_counts",
    "sensitivity": "sensitivity_counts_per_g",
    "verification_error": "verification_error_mg",
    "pose_noise": "pose_noise_counts",
    "gyro_bias": "gyro_bias_dps",
    "link_loss": "link_loss",
    "writeback": "writeback_relative_error",
    "unit_output": "verification_error_mg",
    "gyro_scale": "gyro_scale_error",
    "gyro_misalignment": "gyro_misalignment",
    "gyro_verification": "gyro_verification_deg",
}
UNITS = {
    "offset": "counts",
    "sensitivity": "counts/g",
    "verification_error": "mg",
    "pose_noise": "counts",
    "gyro_bias": "deg/s",
    "link_loss": "",
    "writeback": "",
    "unit_output": "mg",
    "gyro_scale": "",
    "gyro_misalignment": "",
    "gyro_verification": "deg",
}


def check(
    profile: LimitsProfile,
    code: str,
    measured: float,
    *,
    axis: Axis | None = None,
    pose: int | None = None,
    uncertainty: float | None = None,
) -> FailureReason | None:
    """Compare ``measured`` with the profile's bounds for ``code``, by the profile's
    decision rule: ``simple``, within the bounds; ``guarded``, with the value's expanded
    ``uncertainty`` U (when known) as a guard band, ``measured ± U`` within them.

    Returns ``None`` when accepted (or when the profile sets no bounds for an optional
    check), else the failure reason.
    """
    bounds: Bounds | None = getattr(profile, CHECKS[code])
    if bounds is None:
        return None
    where = "".join([f" {axis}" if axis else "", f" (pose {pose + 1})" if pose is not None else ""])
    unit = f" {UNITS[code]}" if UNITS[code] else ""
    guard = None
    if bounds.contains(measured):
        if profile.rule == "simple" or uncertainty is None or bounds.guarded(measured, uncertainty):
            return None
        guard = uncertainty
        outcome = (
            f"within {bounds.describe()} but less than its U = {uncertainty:.3g}{unit} inside "
            "(guarded acceptance, w = U)"
        )
    else:
        outcome = f"outside {bounds.describe()}"
    return FailureReason(
        code=code,
        message=f"{code.replace('_', ' ')}{where} {measured:.6g}{unit} {outcome}",
        measured=measured if math.isfinite(measured) else None,
        lower=bounds.lower,
        upper=bounds.upper,
        axis=axis,
        pose=pose,
        uncertainty=guard,
    )


def load_profiles(path: Path | None = None) -> dict[str, LimitsProfile]:
    """All profiles of a TOML file (the shipped file when ``path`` is None)."""
    if path is None:
        return parse_profiles(shipped_text("limits.toml"), "station/domain/profiles/limits.toml")
    return parse_profiles(read_text(path, "limits file"), str(path))


def parse_profiles(text: str, shown: str) -> dict[str, LimitsProfile]:
    """All profiles of the TOML ``text`` of a limits file (``shown``: its name in errors).

    Whatever the text, the only error is an :class:`InputError` of one line: a file
    nested deeper than the TOML reader's recursion goes (``x = [[[…]]]`` 900 deep) is
    one, not a ``RecursionError``.
    """
    data = parse_toml(text, shown)
    tables = data.get("profiles")
    if not isinstance(tables, dict) or not tables:
        raise InputError(f"{shown}: no [profiles.NAME] tables")
    profiles = {}
    for name, table in tables.items():
        if not isinstance(table, dict):
            raise InputError(f"{shown}: profiles.{name} is not a table ([profiles.{name}])")
        try:
            profiles[name] = LimitsProfile.model_validate({"name": name, **table})
        except ValidationError as exc:
            first = exc.errors()[0]
            field = ".".join(str(p) for p in first["loc"])
            raise InputError(f"{shown}: profile {name}: {field}: {first['msg']}") from None
    return profiles


def load_profile(path: Path | None = None, name: str | None = None) -> LimitsProfile:
    """One profile by name (default: the only one, or ``kxm52-production``)."""
    return pick_profile(load_profiles(path), name)


def pick_profile(profiles: dict[str, LimitsProfile], name: str | None = None) -> LimitsProfile:
    """One of ``profiles`` by name (default: the only one, or ``kxm52-production``)."""
    if name is None:
        name = next(iter(profiles)) if len(profiles) == 1 else DEFAULT_PROFILE
    try:
        return profiles[name]
    except KeyError:
        known = ", ".join(sorted(profiles))
        raise InputError(f"limits profile {name!r} not found (known: {known})") from None
