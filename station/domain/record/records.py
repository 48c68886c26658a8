"""The run record: what one calibration attempt of one unit leaves behind.

The station builds a :class:`RunRecord` at the end of every run (pass or fail) and hands
it to a :class:`station.results.storage.RunStore`; the results server accepts the same model on
``POST /api/v1/runs`` and the database stores it field for field. One model, three places.

Units: accelerometer values in the product sensor's ADC counts (0…4095 for the putter,
0…65535 at most), sensitivities in counts/g, the matrix maps counts to g
(``g = matrix @ (raw − offset)``), gyro rates in deg/s, temperatures in °C, residuals
and errors in mg (1 mg = 0.001 g), times in UTC.
"""

import hashlib
import json
import math
from collections.abc import Callable, Mapping, Sequence
from datetime import UTC, datetime, timedelta
from typing import Annotated, Final, Literal, Self
from uuid import UUID

from pydantic import (
    AfterValidator,
    AwareDatetime,
    BaseModel,
    ConfigDict,
    Field,
    JsonValue,
    SerializerFunctionWrapHandler,
    StringConstraints,
    model_serializer,
    model_validator,
)

from station.domain.arrays import FloatArray
from station.domain.calibration.model import Model
from station.domain.constants import (
    DEFAULT_PART_NUMBER,
    MAX_SLOTS,
    Identifier,
    PartNumber,
    ReviewDecision,
)
from station.domain.gyro.fit import GyroFitReport
from station.domain.gyro.log import GyroDwells
from station.domain.gyro.still import GyroStillSummary
from station.domain.sensors.record_bounds import (
    ADC_SPAN,
    GYRO_RANGE_DPS,
    GYRO_SPAN_DPS,
    MATRIX_MAX_G_PER_COUNT,
    OFFSET_MAX_COUNTS,
    OFFSET_MIN_COUNTS,
    RUN_MAX_DAYS,
    SENSITIVITY_MAX_COUNTS_PER_G,
    WIRE_COUNTS_MAX,
    ConditionNumber,
    ErrorMg,
    GyroSpread,
    Measure,
    Temperature,
    Text,
    plain_document,
    printable,
)
from station.domain.sensors.sensor import ADC_MIN, Axis
from station.domain.signals.samples import WindowSummary

Verdict = Literal["pass", "fail"]
#: Where a unit goes after a run: out of the door, back on a station, or to the repair bench.
Disposition = Literal["ship", "retest", "rework"]
#: ``fit`` poses feed the calibration solve; ``verify`` poses only check its result.
PoseRole = Literal["fit", "verify"]
#: How a value and its uncertainty are judged against a limit (ILAC-G8:09/2019, JCGM
#: 106:2012): ``simple`` acceptance (the value within the limits), or ``guarded``
#: acceptance with a guard band w = U (the value ± U within the limits).
DecisionRule = Literal["simple", "guarded"]

#: The checks a ``guarded`` decision rule judged with their U on records that do not
#: name the rule of each check (:attr:`_RunHeader.check_rules` None: stored before the
#: gyro matrix K and the verification error carried their U into the verdict); every
#: other check of such a record was judged by simple acceptance.
GUARDED_BEFORE_CHECK_RULES: Final = ("offset", "sensitivity", "gyro_bias")

#: Largest count a database INTEGER column holds.
_INT32_MAX = 2**31 - 1

#: A unit's serial number: letters, digits, ``.``, ``_``, ``-``; at most 64 characters.
SERIAL_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9._\-]{0,63}$"

Serial = Annotated[str, StringConstraints(pattern=SERIAL_PATTERN)]

Count = Annotated[int, Field(ge=0, le=_INT32_MAX)]


def _utc(moment: datetime) -> datetime:
    try:
        return moment.astimezone(UTC)
    except OverflowError:
        raise ValueError("is outside the years 1…9999 in UTC") from None


UtcDatetime = Annotated[AwareDatetime, AfterValidator(_utc)]
"""A moment with its time zone, normalised to UTC."""


class _Record(BaseModel):
    """Base of every part of a run record: immutable, strict about unknown fields."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)


class Vector3(_Record):
    """One value per axis."""

    x: float
    y: float
    z: float

    def as_tuple(self) -> tuple[float, float, float]:
        """The three components in axis order."""
        return (self.x, self.y, self.z)

    @classmethod
    def of(cls, values: Sequence[float] | FloatArray) -> Self:
        """The vector of three values in axis order."""
        return cls(x=float(values[0]), y=float(values[1]), z=float(values[2]))


def _within(
    lower: float, upper: float, what: str, *, above: bool = False
) -> Callable[[Vector3], Vector3]:
    """A check that every component lies within ``lower…upper`` (above ``lower`` if
    ``above``), naming the first axis outside (bounds:
    :mod:`station.domain.sensors.record_bounds`)."""

    def check(vector: Vector3) -> Vector3:
        for axis, value in zip("xyz", vector.as_tuple(), strict=True):
            if not (lower < value if above else lower <= value) or not value <= upper:
                raise ValueError(f"{axis} {value:.6g} outside {what} {lower:g}…{upper:g}")
        return vector

    return check


Counts3 = Annotated[Vector3, AfterValidator(_within(ADC_MIN, WIRE_COUNTS_MAX, "the ADC range"))]
"""One ADC reading per axis, within the widest converter's range (counts): the wire's
0…65535, which the 16-bit product fills (the 12-bit putter's 0…4095 within it)."""

Spread3 = Annotated[Vector3, AfterValidator(_within(0, ADC_SPAN, "the ADC span"))]
"""A spread of ADC readings per axis (counts)."""

GyroRate3 = Annotated[
    Vector3, AfterValidator(_within(-GYRO_RANGE_DPS, GYRO_RANGE_DPS, "the gyro range"))
]
"""One gyro reading or mean per axis (deg/s)."""

GyroSpread3 = Annotated[Vector3, AfterValidator(_within(0, GYRO_SPAN_DPS, "the gyro span"))]
"""A spread of gyro readings per axis (deg/s)."""

Offset3 = Annotated[
    Vector3, AfterValidator(_within(OFFSET_MIN_COUNTS, OFFSET_MAX_COUNTS, "a zero-g output"))
]
Sensitivity3 = Annotated[
    Vector3, AfterValidator(_within(0, SENSITIVITY_MAX_COUNTS_PER_G, "a sensitivity", above=True))
]


class LinkStats(_Record):
    """Health of the serial link while a pose was captured."""

    crc_errors: Count = 0
    gaps: Count = 0
    resyncs: Count = 0
    lost_samples: Count = 0


class ReplacedCapture(_Record):
    """A capture of a pose that was thrown away and taken again, kept for audit."""

    captured_at: UtcDatetime
    reason: Text
    mean: Counts3
    std: Spread3
    sample_count: Count


class PoseRecord(_Record):
    """One still pose: the accepted capture's statistics (counts, deg/s, °C)."""

    index: Count
    name: Identifier
    role: PoseRole = "fit"
    mean: Counts3
    std: Spread3
    sample_count: Annotated[int, Field(ge=1, le=_INT32_MAX)]
    gyro_mean: GyroRate3 | None = None
    temperature_c: Temperature | None = None
    link: LinkStats = LinkStats()
    replaced: tuple[ReplacedCapture, ...] = ()

    @classmethod
    def of_window(
        cls,
        summary: WindowSummary,
        *,
        index: int,
        name: str,
        role: PoseRole,
        link: LinkStats | None = None,
        replaced: tuple[ReplacedCapture, ...] = (),
    ) -> Self:
        """The record of a still window from its summary (the one place a window's
        statistics become a pose record's)."""
        return cls(
            index=index,
            name=name,
            role=role,
            mean=Vector3.of(summary.accel_mean),
            std=Vector3.of(summary.accel_std),
            sample_count=summary.count,
            gyro_mean=Vector3.of(summary.gyro_mean),
            temperature_c=summary.temperature_c,
            link=link or LinkStats(),
            replaced=replaced,
        )


class FailureReason(_Record):
    """Why a run failed: which check, what was measured, against which bounds.

    ``message`` is the station's sentence as said (English, the record); the other
    fields are what it was made of, from which a reader's language renders it
    (:mod:`station.report.explanations`): ``uncertainty`` is the value's expanded
    uncertainty U when guarded acceptance refused a value inside its bounds
    (:func:`station.domain.product.limits.check`).
    """

    code: Identifier
    message: Text
    measured: Measure | None = None
    lower: Measure | None = None
    upper: Measure | None = None
    axis: Axis | None = None
    pose: Count | None = None
    uncertainty: Measure | None = None


def _matrix_3x3(rows: tuple[tuple[float, ...], ...]) -> tuple[tuple[float, ...], ...]:
    if len(rows) != 3 or any(len(row) != 3 for row in rows):
        raise ValueError("must be 3 rows of 3 numbers")
    if not all(math.isfinite(value) for row in rows for value in row):
        raise ValueError("must hold finite numbers")
    bound = MATRIX_MAX_G_PER_COUNT
    for i, j in ((i, j) for i in range(3) for j in range(3)):
        if not -bound <= rows[i][j] <= bound:
            raise ValueError(f"[{i}][{j}] {rows[i][j]:.6g} outside {-bound:g}…{bound:g} g/count")
    return rows


Matrix3 = Annotated[tuple[tuple[float, ...], ...], AfterValidator(_matrix_3x3)]


class Coefficients(_Record):
    """The calibration written into the unit (``g = matrix @ (raw − offset)``)."""

    offset: Offset3
    sensitivity: Sensitivity3
    matrix: Matrix3


_Stored3 = tuple[float, float, float]


class StoredCoefficients(_Record):
    """One set of coefficients as the unit stored it (``docs/protocol.md``, READ_CAL and
    READ_GYRO_CAL): ``written`` False while the unit holds its factory defaults; ``offset``
    and ``matrix`` as read (float32 values, whatever the unit held: no bounds but being
    finite). The accelerometer's read ``g = matrix @ (raw − offset)`` (counts, g/count),
    the gyros' ``rate = matrix @ (measured − offset)`` (deg/s, K⁻¹)."""

    written: bool
    offset: _Stored3
    matrix: tuple[_Stored3, _Stored3, _Stored3]


class AsFound(_Record):
    """What the unit held when the station received it (ISO/IEC 17025:2017 7.8.4.1, the
    results before adjustment): its coefficients read before the run wrote any, at
    ``read_at`` (the unit's receipt at the station); ``gyro`` on whole-unit runs."""

    read_at: UtcDatetime
    accelerometer: StoredCoefficients
    gyro: StoredCoefficients | None = None


class QualityMetrics(_Record):
    """How well the calibration explains the poses.

    ``excluded_poses``: the fit poses (0-based, as ``PoseRecord.index``) the solve left
    out as inconsistent with the others (:mod:`station.domain.calibration.consistency`); left
    out of the record when none was, so older records hash as before.
    """

    residual_rms_mg: ErrorMg
    residual_max_mg: ErrorMg
    condition_number: ConditionNumber
    verification_error_mg: ErrorMg | None = None
    excluded_poses: tuple[Count, ...] | None = None


class GyroSummary(_Record):
    """Gyro figures over the still poses (deg/s); stored as one JSON document.

    ``bias`` is each gyro's mean over the poses and ``noise`` its RMS spread; ``still``
    the full analysis of :func:`station.domain.gyro.summarize_still_poses`, with each gyro's
    bias-vs-gravity slope (deg/s/g) and whether it is consistent with zero, as the
    g-sensitivity study says it should be for a still unit.
    """

    bias: GyroRate3
    noise: GyroSpread3
    still: GyroStillSummary | None = None


#: Largest magnitude of a stored gyro-matrix element (K is I within a few %).
GYRO_MATRIX_MAX: Final = 2.0
GyroMatrixEntry = Annotated[float, Field(ge=-GYRO_MATRIX_MAX, le=GYRO_MATRIX_MAX)]
GyroMatrixError = Annotated[float, Field(ge=0, le=GYRO_MATRIX_MAX)]
AngleDeg = Annotated[float, Field(ge=0, le=180)]
_Row = tuple[GyroMatrixEntry, GyroMatrixEntry, GyroMatrixEntry]
_ErrorRow = tuple[GyroMatrixError, GyroMatrixError, GyroMatrixError]


class GyroMove(_Record):
    """One move between two still poses (indexes of the run's poses) and its residual.

    ``residual_deg`` is the angle between gravity's direction in the pose before the
    move and the one after, carried back by the rotation integrated from the corrected
    gyros; ``unusable`` says why a move was left out of the fit (samples lost, the
    stream restarted, a pose taken again), and then there is no residual.
    """

    before: Count
    after: Count
    residual_deg: AngleDeg | None = None
    unusable: Text | None = None


class GyroMatrixRecord(_Record):
    """The gyro matrix the station fitted from the moves and wrote into the unit.

    Model ([Tedaldi2014]_): the gyros read ``measured = bias + K·ω`` (deg/s), ω the true
    rate in the calibrated accelerometer's frame. ``matrix`` is K (row = gyro, column =
    rate axis), ``standard_errors`` the 1-σ of each element (None with no redundancy),
    ``bias_dps`` the bias over the still poses. The unit holds ``bias_dps`` and K⁻¹
    (``docs/protocol.md``). ``g_sensitivity_removed`` says whether a stored [Park2014]_
    fit's 1 g term was taken out of the rates first; ``verification_deg`` is the check
    of the unit's own calibrated gyros over the verification move.
    """

    matrix: tuple[_Row, _Row, _Row]
    standard_errors: tuple[_ErrorRow, _ErrorRow, _ErrorRow] | None = None
    bias_dps: GyroRate3
    moves: Annotated[tuple[GyroMove, ...], Field(max_length=128)] = ()
    residual_rms_deg: AngleDeg
    condition_number: ConditionNumber
    g_sensitivity_removed: bool = False
    verification_deg: AngleDeg | None = None


_MatrixSpread = Annotated[float, Field(ge=0, le=2 * GYRO_MATRIX_MAX)]
_SpreadRow = tuple[_MatrixSpread, _MatrixSpread, _MatrixSpread]
_MatrixU = Annotated[float, Field(ge=0, le=MATRIX_MAX_G_PER_COUNT)]
_MatrixURow = tuple[_MatrixU, _MatrixU, _MatrixU]


class UncertaintyRecord(_Record):
    """Expanded uncertainties U = k·u_c of the run's coefficients ([JCGM100]_), in the
    sensor's units (:mod:`station.domain.calibration.uncertainty`): offsets in counts,
    sensitivities in counts/g, gyro biases in deg/s, the gyro matrix K as a fraction, the
    verification pose's error in mg, the nine-parameter model's matrix C in g/count. A
    value the run did not measure is left out (None), so a record from before a value
    was added hashes as it did."""

    k: Annotated[float, Field(gt=0, le=10, description="coverage factor (2: about 95 %)")]
    offset: Annotated[Spread3 | None, Field(description="U of each offset, counts")] = None
    sensitivity: Annotated[Spread3 | None, Field(description="U of each sensitivity, counts/g")] = (
        None
    )
    gyro_bias_dps: Annotated[
        tuple[GyroSpread, GyroSpread, GyroSpread] | None,
        Field(description="U of each gyro's bias, deg/s"),
    ] = None
    gyro_matrix: Annotated[
        tuple[_SpreadRow, _SpreadRow, _SpreadRow] | None,
        Field(description="U of each element of the gyro matrix K"),
    ] = None
    verification_error_mg: Annotated[
        ErrorMg | None,
        Field(
            description="U of the verification pose's error ||g| − 1|, mg: the calibrated "
            "output's U at that pose and the pose's own noise (docs/calibration.md)"
        ),
    ] = None
    matrix: Annotated[
        tuple[_MatrixURow, _MatrixURow, _MatrixURow] | None,
        Field(
            description="U of each entry of the nine-parameter model's counts-to-g matrix C, "
            "g/count (upper-triangular: zero below the diagonal)"
        ),
    ] = None
    excluded_influences: Annotated[
        tuple[Literal["temperature", "gyro_bias_repeatability"], ...] | None,
        Field(
            description="influences U leaves out, named (docs/calibration.md): temperature "
            "(no temperature at the poses), gyro_bias_repeatability (none declared for the "
            "product's gyros)"
        ),
    ] = None

    @model_serializer(mode="wrap")
    def _measured_only(self, handler: SerializerFunctionWrapHandler) -> dict[str, object]:
        """Unmeasured coefficients are left out of the shape, not given as null."""
        document: dict[str, object] = handler(self)
        return {key: value for key, value in document.items() if value is not None}

    def to_json(self) -> dict[str, JsonValue]:
        """The one shape: ``{"k", "offset": {x,y,z}, "sensitivity": {x,y,z},
        "gyro_bias_dps": [3], "gyro_matrix": [[3×3]]}``, unmeasured keys left out."""
        return self.model_dump(mode="json")


def document_sha256(document: Mapping[str, JsonValue]) -> str:
    """SHA-256 of a JSON document's canonical text (sorted keys, no whitespace, ASCII):
    a limits profile's identity (:attr:`station.domain.product.limits.LimitsProfile.sha256`)."""
    return hashlib.sha256(canonical_json(document).encode()).hexdigest()


def canonical_json(document: Mapping[str, JsonValue]) -> str:
    """The canonical text of a JSON document, the one its SHA-256 is taken over."""
    return json.dumps(document, sort_keys=True, separators=(",", ":"))


class LimitsRef(_Record):
    """The named, versioned limits profile the verdict was taken against.

    ``profile``, the profile's canonical document, travels with the run so the results
    server stores the bounds themselves the first time a run uses them (keyed by
    ``sha256``); records from older stations carry only the reference.
    """

    name: Identifier
    version: Identifier
    sha256: Annotated[str, StringConstraints(pattern=r"^[0-9a-f]{64}$")]
    profile: dict[str, JsonValue] | None = Field(
        default=None,
        description="the limits profile itself (its canonical JSON document, as "
        "station.domain.product.limits.LimitsProfile): its SHA-256 must be `sha256`, its name and "
        "version `name` and `version`",
    )

    @model_validator(mode="after")
    def _profile_is_the_referenced_one(self) -> Self:
        if self.profile is None:
            return self
        if self.profile.get("name") != self.name or self.profile.get("version") != self.version:
            raise ValueError("the profile's name and version are not the reference's")
        if document_sha256(self.profile) != self.sha256:
            raise ValueError("the profile's SHA-256 is not `sha256`")
        return self


class _RunHeader(_Record):
    """What identifies a run and its outcome: everything but the per-pose detail."""

    run_id: UUID
    serial: Serial
    station_id: Identifier
    operator_id: Identifier
    #: The unit's production lot, when the station was told it (``calstation run --lot``).
    lot: Identifier | None = None
    #: The unit's product (``station.domain.product.products``); records from before products
    #: existed were all of the default one.
    part_number: PartNumber = DEFAULT_PART_NUMBER
    #: The fixture's slot the unit was calibrated in, from 1 (a one-port station is a
    #: fixture of one slot: 1); None on records from before slots were recorded.
    fixture_slot: int | None = Field(None, ge=1, le=MAX_SLOTS)
    started_at: UtcDatetime
    finished_at: UtcDatetime
    software_version: Identifier
    algorithm: Identifier
    model: Model
    limits: LimitsRef
    verdict: Verdict
    #: Where the unit goes next (:mod:`station.domain.record.unit_state`); None on records from
    #: before.
    disposition: Disposition | None = None
    #: ``golden``: the station's golden-unit check (``docs/station.md``), not a production
    #: unit; None for production runs and records from before.
    purpose: Literal["golden"] | None = None
    failures: tuple[FailureReason, ...] = ()
    coefficients: Coefficients | None = None
    quality: QualityMetrics | None = None
    gyro: GyroSummary | None = None
    #: The gyro matrix K fitted from the moves (whole-unit runs); None otherwise.
    gyro_matrix: GyroMatrixRecord | None = None
    #: Expanded uncertainties of the coefficients; None on runs without coefficients and
    #: records from before.
    uncertainty: UncertaintyRecord | None = None
    #: The decision rule that judged the run (ILAC-G8): ``simple`` acceptance or
    #: ``guarded`` (guard band w = U); None on records from before (they were simple).
    decision_rule: DecisionRule | None = None
    #: The coefficients the unit held before the run wrote its own (as-found); None on
    #: records from before the station read them.
    as_found: AsFound | None = None
    #: The decision rule that judged each limit of the profile, by check code
    #: (``station.domain.product.limits.CHECKS``): ``guarded`` where the profile's rule is and the
    #: value's U (``uncertainty``) was known, else ``simple``. None on records from
    #: before (their rule, :data:`GUARDED_BEFORE_CHECK_RULES`, :meth:`rule_of`); left
    #: out of the record's JSON when None, so they hash and verify as they did.
    check_rules: dict[Identifier, DecisionRule] | None = Field(
        None, exclude_if=lambda rules: rules is None
    )

    def rule_of(self, code: str) -> DecisionRule:
        """The decision rule that judged check ``code`` (ILAC-G8:09/2019): the record's
        own (:attr:`check_rules`), or on a record from before, its run's rule for the
        checks it guarded then and simple acceptance for the others."""
        if self.check_rules is not None:
            return self.check_rules.get(code, "simple")
        if code in GUARDED_BEFORE_CHECK_RULES:
            return self.decision_rule or "simple"
        return "simple"

    @model_validator(mode="after")
    def _consistent_outcome(self) -> Self:
        if self.finished_at < self.started_at:
            raise ValueError("finished_at is before started_at")
        if self.finished_at - self.started_at > timedelta(days=RUN_MAX_DAYS):
            raise ValueError(f"finished_at is more than {RUN_MAX_DAYS} days after started_at")
        if self.verdict == "pass" and self.failures:
            raise ValueError("a passing run has no failure reasons")
        if self.verdict == "fail" and not self.failures:
            raise ValueError("a failing run needs at least one failure reason")
        if self.verdict == "pass" and self.coefficients is None:
            raise ValueError("a passing run needs its coefficients")
        return self


class RunRecord(_RunHeader):
    """One calibration attempt of one unit at one station: what the station submits."""

    poses: Annotated[tuple[PoseRecord, ...], Field(min_length=1, max_length=64)]

    @model_validator(mode="after")
    def _poses_numbered(self) -> Self:
        indexes = sorted(pose.index for pose in self.poses)
        if indexes != list(range(len(indexes))):
            raise ValueError("pose indexes must be 0…N-1, each once")
        return self

    def counts_beyond(self, adc_max: int) -> str | None:
        """The first pose mean above ``adc_max``, the largest count of the record's
        product's sensor (the putter's 4095), named with its field; None when all are
        within. The record holds only the wire's bounds (:data:`Counts3`): which sensor a
        part number has is the product catalogue's, known to the caller."""
        for i, pose in enumerate(self.poses):
            means = [("mean", pose.mean)]
            means += [(f"replaced.{j}.mean", r.mean) for j, r in enumerate(pose.replaced)]
            for where, mean in means:
                for axis, value in zip("xyz", mean.as_tuple(), strict=True):
                    if value > adc_max:
                        return (
                            f"poses.{i}.{where}: {axis} {value:.6g} outside the ADC range "
                            f"0…{adc_max} of {self.part_number}"
                        )
        return None

    def fit_poses(self) -> tuple[PoseRecord, ...]:
        """The poses that feed the calibration solve, in index order."""
        return tuple(sorted((p for p in self.poses if p.role == "fit"), key=lambda p: p.index))


class RunSummary(_RunHeader):
    """A stored run without its poses (lists, histories, a unit's current state)."""

    received_at: UtcDatetime


class StoredRun(RunRecord):
    """A run as the plant's record holds it: the submitted record and when it arrived."""

    received_at: UtcDatetime


LogSource = Annotated[
    str, StringConstraints(min_length=1, max_length=255), AfterValidator(printable)
]
"""The rate-table / centrifuge log a gyro fit was made from."""


class GyroFitRecord(_Record):
    """A unit's gyro error-model fit from a rate-table / centrifuge log, as stored."""

    serial: Serial
    fitted_at: UtcDatetime
    source: LogSource
    report: Annotated[GyroFitReport, AfterValidator(plain_document)]
    #: The log's dwells, kept to draw the fit's scale-factor plot (certificate).
    dwells: Annotated[GyroDwells, AfterValidator(plain_document)] | None = None


def _not_blank(text: str) -> str:
    """``text`` without the spaces around it; ValueError if nothing else is left."""
    stripped = text.strip()
    if not stripped:
        raise ValueError("must not be blank")
    return stripped


Reason = Annotated[
    str,
    StringConstraints(min_length=1, max_length=500),
    AfterValidator(printable),
    AfterValidator(_not_blank),
]
"""A person's reason for a decision: one line, not blank (the spaces around it dropped;
a line break, leading or trailing, is refused like any control character)."""


class HoldReview(_Record):
    """A quality review of a unit on hold: an append-only record of why its latest run
    (``run_id``) failed (``root_cause``), what was repaired (``repair_action``), who
    reviewed it and when, and what it decided: calibrate it again (``retest``: its
    retest limit counts afresh from here) or ``scrap`` it. A unit sent to rework is
    not calibrated again until a review releases it."""

    serial: Serial
    run_id: UUID
    reviewed_at: UtcDatetime
    reviewer: Identifier
    root_cause: Reason
    repair_action: Reason
    decision: ReviewDecision
