"""The run record: what one calibration attempt of one unit leaves behind.

The station builds a :class:`RunRecord` at the end of every run (pass or fail) and hands
it to a :class:`station.storage.RunStore`; the results server accepts the same model on
``POST /api/v1/runs`` and the database stores it field for field. One model, three places.

Units: accelerometer values in ADC counts (0…4095), sensitivities in counts/g, the
matrix maps counts to g (``g = matrix @ (raw − offset)``), gyro rates in deg/s,
temperatures in °C, residuals and errors in mg (1 mg = 0.001 g), times in UTC.
"""

import math
import re
from datetime import UTC, datetime
from typing import Annotated, Literal, Self
from uuid import UUID

from pydantic import (
    AfterValidator,
    AwareDatetime,
    BaseModel,
    ConfigDict,
    Field,
    StringConstraints,
    model_validator,
)

from station.gyro.fit import GyroFitReport
from station.gyro.log import GyroDwells
from station.gyro.still import GyroStillSummary
from station.sensor import ADC_MAX, ADC_MIN

__all__ = [
    "SERIAL_PATTERN",
    "Coefficients",
    "Counts3",
    "Disposition",
    "FailureReason",
    "GyroFitRecord",
    "GyroSummary",
    "LimitsRef",
    "LinkStats",
    "Matrix3",
    "Model",
    "PoseRecord",
    "PoseRole",
    "QualityMetrics",
    "ReplacedCapture",
    "RunRecord",
    "RunSummary",
    "StoredRun",
    "UtcDatetime",
    "Vector3",
    "Verdict",
]

Verdict = Literal["pass", "fail"]
#: Where a unit goes after a run: out of the door, back on a station, or to the repair bench.
Disposition = Literal["ship", "retest", "rework"]
Model = Literal["six", "nine"]
Axis = Literal["x", "y", "z"]
#: ``fit`` poses feed the calibration solve; ``verify`` poses only check its result.
PoseRole = Literal["fit", "verify"]

#: Largest count a database INTEGER column holds.
_INT32_MAX = 2**31 - 1

#: A unit's serial number: letters, digits, ``.``, ``_``, ``-``; at most 64 characters.
SERIAL_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9._\-]{0,63}$"

Serial = Annotated[str, StringConstraints(pattern=SERIAL_PATTERN)]

Identifier = Annotated[str, StringConstraints(pattern=r"^[A-Za-z0-9][A-Za-z0-9._:@\-]{0,63}$")]
"""A station, operator, algorithm or limits-profile name."""

_PRINTABLE = re.compile(r"^[^\x00-\x1f\x7f]*$")


def _printable(text: str) -> str:
    if not _PRINTABLE.match(text):
        raise ValueError("must not contain control characters")
    return text


Text = Annotated[str, StringConstraints(max_length=500), AfterValidator(_printable)]
"""Free text for people (messages, reasons): one line, no control characters."""

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


def _within_adc(counts: Vector3) -> Vector3:
    if not all(ADC_MIN <= value <= ADC_MAX for value in counts.as_tuple()):
        raise ValueError(f"counts must lie within the ADC range {ADC_MIN}…{ADC_MAX}")
    return counts


Counts3 = Annotated[Vector3, AfterValidator(_within_adc)]
"""One ADC reading per axis, within the converter's range (counts)."""


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
    std: Vector3
    sample_count: Count


class PoseRecord(_Record):
    """One still pose: the accepted capture's statistics (counts, deg/s, °C)."""

    index: Count
    name: Identifier
    role: PoseRole = "fit"
    mean: Counts3
    std: Vector3
    sample_count: Annotated[int, Field(ge=1, le=_INT32_MAX)]
    gyro_mean: Vector3 | None = None
    temperature_c: float | None = None
    link: LinkStats = LinkStats()
    replaced: tuple[ReplacedCapture, ...] = ()


class FailureReason(_Record):
    """Why a run failed: which check, what was measured, against which bounds."""

    code: Identifier
    message: Text
    measured: float | None = None
    lower: float | None = None
    upper: float | None = None
    axis: Axis | None = None
    pose: Count | None = None


def _matrix_3x3(rows: tuple[tuple[float, ...], ...]) -> tuple[tuple[float, ...], ...]:
    if len(rows) != 3 or any(len(row) != 3 for row in rows):
        raise ValueError("must be 3 rows of 3 numbers")
    if not all(math.isfinite(value) for row in rows for value in row):
        raise ValueError("must hold finite numbers")
    return rows


Matrix3 = Annotated[tuple[tuple[float, ...], ...], AfterValidator(_matrix_3x3)]


class Coefficients(_Record):
    """The calibration written into the unit (``g = matrix @ (raw − offset)``)."""

    offset: Vector3
    sensitivity: Vector3
    matrix: Matrix3


class QualityMetrics(_Record):
    """How well the calibration explains the poses."""

    residual_rms_mg: Annotated[float, Field(ge=0)]
    residual_max_mg: Annotated[float, Field(ge=0)]
    condition_number: Annotated[float, Field(ge=1)]
    verification_error_mg: Annotated[float, Field(ge=0)] | None = None


class GyroSummary(_Record):
    """Gyro figures over the still poses (deg/s); stored as one JSON document.

    ``bias`` is each gyro's mean over the poses and ``noise`` its RMS spread; ``still``
    the full analysis of :func:`station.gyro.summarize_still_poses`, with each gyro's
    bias-vs-gravity slope (deg/s/g) and whether it is consistent with zero, as the
    g-sensitivity study says it should be for a still unit.
    """

    bias: Vector3
    noise: Vector3
    still: GyroStillSummary | None = None


class LimitsRef(_Record):
    """The named, versioned limits profile the verdict was taken against."""

    name: Identifier
    version: Identifier
    sha256: Annotated[str, StringConstraints(pattern=r"^[0-9a-f]{64}$")]


class _RunHeader(_Record):
    """What identifies a run and its outcome: everything but the per-pose detail."""

    run_id: UUID
    serial: Serial
    station_id: Identifier
    operator_id: Identifier
    #: The unit's production lot, when the station was told it (``calstation run --lot``).
    lot: Identifier | None = None
    started_at: UtcDatetime
    finished_at: UtcDatetime
    software_version: Identifier
    algorithm: Identifier
    model: Model
    limits: LimitsRef
    verdict: Verdict
    #: Where the unit goes next (:mod:`station.unit_state`); None on records from before.
    disposition: Disposition | None = None
    failures: tuple[FailureReason, ...] = ()
    coefficients: Coefficients | None = None
    quality: QualityMetrics | None = None
    gyro: GyroSummary | None = None

    @model_validator(mode="after")
    def _consistent_outcome(self) -> Self:
        if self.finished_at < self.started_at:
            raise ValueError("finished_at is before started_at")
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

    def fit_poses(self) -> tuple[PoseRecord, ...]:
        """The poses that feed the calibration solve, in index order."""
        return tuple(sorted((p for p in self.poses if p.role == "fit"), key=lambda p: p.index))


class RunSummary(_RunHeader):
    """A stored run without its poses (lists, histories, a unit's current state)."""

    received_at: UtcDatetime


class StoredRun(RunRecord):
    """A run as the plant's record holds it: the submitted record and when it arrived."""

    received_at: UtcDatetime


class GyroFitRecord(_Record):
    """A unit's gyro error-model fit from a rate-table / centrifuge log, as stored."""

    serial: Serial
    fitted_at: UtcDatetime
    source: Annotated[
        str, StringConstraints(min_length=1, max_length=255), AfterValidator(_printable)
    ]
    report: GyroFitReport
    #: The log's dwells, kept to draw the fit's scale-factor plot (certificate).
    dwells: GyroDwells | None = None
