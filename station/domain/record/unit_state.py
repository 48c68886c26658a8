"""What a unit holds and where it goes next, read from its runs.

A run is one *attempt*. Not every attempt changes the unit:

- it **wrote** the unit when its coefficients went into the unit's flash and read back
  equal. A run that failed before the write-back (aborted by the operator, a solve that
  failed, an axis at its rail) or whose write-back failed wrote nothing verified, so the
  unit still holds what the last run that wrote it put there (:func:`wrote_unit`);
- it **counts** as evidence about the unit unless the operator aborted it: an abort says
  nothing about the unit (:func:`counts`). The station never records an abort after the
  write-back as ``aborted`` (the unit's output check is then the failure), so an abort
  always wrote nothing.

A unit's answer (:class:`UnitCalibration`, ``GET /api/v1/units/{serial}``) keeps the
two apart: ``holds`` (the last verified write-back) and ``latest`` (the latest attempt),
with the unit's ``verdict`` taken from its latest attempt that counts, the same rule the
end-of-line report applies (:mod:`db.rollups`).

The station uses the same rules at the scan (a unit that passed already, a unit past
its retest limit) and at the verdict (:func:`disposition`).
"""

from collections.abc import Sequence
from datetime import datetime
from typing import Annotated, Any, Protocol, TypeVar
from uuid import UUID

from pydantic import BaseModel, ConfigDict, Field

from station.domain.calibration.model import Model
from station.domain.record.records import (
    Disposition,
    FailureReason,
    GyroMatrixRecord,
    GyroSummary,
    HoldReview,
    LimitsRef,
    Matrix3,
    QualityMetrics,
    RunRecord,
    RunSummary,
    StoredRun,
    UncertaintyRecord,
    Vector3,
    Verdict,
)

__all__ = [
    "ABORTED",
    "DEFAULT_RETEST_LIMIT",
    "HeldCalibration",
    "UnitAttempt",
    "UnitCalibration",
    "counts",
    "deciding_review",
    "disposition",
    "wrote_unit",
]

Run = RunRecord | RunSummary | StoredRun


class RunOutcome(Protocol):
    """What a run's disposition is decided on: its verdict and its failures (a run,
    or a run's verdict before its record is made)."""

    @property
    def verdict(self) -> Verdict: ...

    @property
    def failures(self) -> Sequence[FailureReason]: ...


#: Failure code of a run the operator aborted.
ABORTED = "aborted"
#: Failure codes of runs that ended before a verified write-back.
UNWRITTEN = frozenset({ABORTED, "calibration", "gyro_matrix", "saturated", "writeback"})
#: Failure codes that say the unit itself is broken: no retest will fix it.
BROKEN = frozenset({"saturated", "writeback"})
#: Attempts per unit (aborts not counted) when the limits profile sets none.
DEFAULT_RETEST_LIMIT = 3


def wrote_unit(run: Run) -> bool:
    """Whether the run's coefficients went into the unit and read back equal."""
    if run.coefficients is None:
        return False
    return not any(f.code in UNWRITTEN for f in run.failures)


def counts(run: RunOutcome) -> bool:
    """Whether the run is evidence about the unit (every run but an operator's abort)."""
    return not any(f.code == ABORTED for f in run.failures)


def disposition(run: RunOutcome, earlier: Sequence[Run], retest_limit: int) -> Disposition:
    """Where the unit goes after ``run``, given its ``earlier`` runs (oldest first).

    A pass ships. An abort leaves the unit as it was: a unit that passed before and holds
    that pass's coefficients ships, any other goes back to be calibrated. A failure that
    shows the unit broken (an axis at its rail, a write-back that did not hold) goes to
    rework, so does a failure that uses up the retest limit (attempts, aborts not
    counted); any other failure is retested.
    """
    if run.verdict == "pass":
        return "ship"
    tried = sum(1 for r in earlier if counts(r))
    if not counts(run):
        before = UnitCalibration.of_history([*earlier]) if earlier else None
        if before is not None and before.verdict == "pass" and before.holds is not None:
            return "ship"
        return "rework" if tried >= retest_limit else "retest"
    if any(f.code in BROKEN for f in run.failures) or tried + 1 >= retest_limit:
        return "rework"
    return "retest"


class _UnitPart(BaseModel):
    model_config = ConfigDict(frozen=True, extra="forbid")


_Part = TypeVar("_Part", bound=_UnitPart)


class HeldCalibration(_UnitPart):
    """The coefficients the unit holds: those of the last run that wrote it."""

    run_id: UUID
    verdict: Annotated[Verdict, Field(description="the verdict of the run that wrote them")]
    written_at: Annotated[datetime, Field(description="when that run finished (UTC)")]
    station_id: str
    model: Model
    limits: LimitsRef
    offset: Annotated[Vector3, Field(description="counts")]
    sensitivity: Annotated[Vector3, Field(description="counts/g")]
    matrix: Annotated[Matrix3, Field(description="counts → g, g = M·(raw − offset)")]
    quality: QualityMetrics | None
    gyro_matrix: Annotated[
        GyroMatrixRecord | None,
        Field(description="the gyro matrix K and bias written (whole-unit runs; None: none)"),
    ] = None
    uncertainty: Annotated[
        UncertaintyRecord | None,
        Field(
            description="expanded uncertainties (k = 2) of the coefficients written, the "
            "sensor's units (None: the run recorded none)"
        ),
    ] = None


class UnitAttempt(_UnitPart):
    """The unit's latest calibration attempt, whatever it wrote."""

    run_id: UUID
    verdict: Verdict
    disposition: Annotated[
        Disposition | None,
        Field(description="where the station sent the unit (None: not recorded)"),
    ]
    started_at: datetime
    finished_at: datetime
    station_id: str
    operator_id: str
    lot: Annotated[str | None, Field(description="the unit's production lot, if known")]
    part_number: Annotated[str, Field(description="the unit's product (its part number)")]
    software_version: str
    model: Model
    limits: LimitsRef
    wrote_unit: Annotated[bool, Field(description="whether it wrote verified coefficients")]
    failures: tuple[FailureReason, ...]


class UnitCalibration(_UnitPart):
    """A unit's current state: what it holds, its latest attempt, and its verdict.

    What ``GET /api/v1/units/{serial}`` answers; the results database keeps it ready,
    serialised, per serial number (:mod:`db.store.units`).
    """

    serial: str
    verdict: Annotated[
        Verdict, Field(description="the verdict of the latest attempt that counts (aborts do not)")
    ]
    attempts: Annotated[int, Field(description="runs of the unit, aborts not counted")]
    holds: Annotated[
        HeldCalibration | None,
        Field(description="the coefficients of the last verified write-back (None: never)"),
    ]
    latest: UnitAttempt
    gyro: Annotated[
        GyroSummary | None,
        Field(description="the gyros over the latest run's still poses: bias, noise, slope vs g"),
    ]

    @classmethod
    def of_history(cls, runs: Sequence[Run]) -> "UnitCalibration":
        """The unit's state given its runs, oldest first (at least one)."""
        latest = runs[-1]
        counted = [r for r in runs if counts(r)]
        writer = next((r for r in reversed(runs) if wrote_unit(r)), None)
        return cls(
            serial=latest.serial,
            verdict=(counted[-1] if counted else latest).verdict,
            attempts=len(counted),
            holds=None if writer is None else _held(writer),
            latest=_attempt(latest),
            gyro=latest.gyro,
        )

    def then(self, run: Run) -> "UnitCalibration":
        """The unit's state after ``run``, a run later than every run this state is of.

        The same as :meth:`of_history` of those runs and ``run`` (a property test holds
        them equal), from this state alone: ``run`` is the latest attempt; it is one more
        attempt and gives the verdict if it counts (the verdict of a unit with no attempt
        that counts is its latest run's); it is what the unit holds if it wrote the unit.
        """
        counted, held = counts(run), _held(run)
        return UnitCalibration(
            serial=run.serial,
            verdict=run.verdict if counted or not self.attempts else self.verdict,
            attempts=self.attempts + counted,
            holds=self.holds if held is None else held,
            latest=_attempt(run),
            gyro=run.gyro,
        )


def deciding_review(runs: Sequence[Run], reviews: Sequence[HoldReview]) -> HoldReview | None:
    """The unit's latest review (``reviews`` oldest first) if it came after its latest run
    (``runs`` oldest first): it decides where the unit goes (released for a retest, or
    scrapped) until the unit is calibrated again."""
    review = reviews[-1] if reviews else None
    if review is None or (runs and review.reviewed_at < runs[-1].finished_at):
        return None
    return review


def _held(writer: Run) -> HeldCalibration | None:
    """What ``writer`` put into the unit; ``None`` if it wrote nothing (:func:`wrote_unit`)."""
    cal = writer.coefficients
    if cal is None or not wrote_unit(writer):
        return None
    return _of_run(
        HeldCalibration,
        writer,
        written_at=writer.finished_at,
        offset=cal.offset,
        sensitivity=cal.sensitivity,
        matrix=cal.matrix,
    )


def _attempt(run: Run) -> UnitAttempt:
    """``run`` as the unit's latest attempt."""
    return _of_run(UnitAttempt, run, wrote_unit=wrote_unit(run))


def _of_run(part: type[_Part], run: Run, **given: Any) -> _Part:
    """A ``part`` of the unit's answer: the fields ``given``, every other one as ``run``
    has it."""
    taken = {name: getattr(run, name) for name in part.model_fields if name not in given}
    return part(**taken, **given)
