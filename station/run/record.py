"""The records a run builds from what it took: each pose, the gyros, the whole run.

Pure functions of the run's journal, solution and verdict, so that
:class:`station.run.unit_run.UnitRun` only decides *when* a record is made.
"""

import logging
from collections.abc import Mapping
from datetime import UTC, datetime
from types import MappingProxyType
from typing import Final

import numpy as np
from pydantic import ValidationError

from station import __version__
from station.domain.arrays import FloatArray as Array
from station.domain.calibration import (
    Model,
    Solution,
    Uncertainty,
    accelerometer_budget,
    apply,
    gyro_bias_uncertainty,
    gyro_matrix_uncertainty,
)
from station.domain.gyro import summarize_still_poses
from station.domain.gyro.motion import GyroMatrixFit
from station.domain.product.limits import LimitsProfile
from station.domain.product.run_settings import RunSettings
from station.domain.record.records import (
    Coefficients,
    DecisionRule,
    Disposition,
    FailureReason,
    GyroMatrixRecord,
    GyroSummary,
    LinkStats,
    PoseRecord,
    PoseRole,
    QualityMetrics,
    ReplacedCapture,
    RunRecord,
    UncertaintyRecord,
    Vector3,
    Verdict,
)
from station.domain.sensors.sensor_spec import SensorSpec
from station.results.journal import Capture, RunJournal
from station.run.acquisition import PoseResult

#: The algorithm a run's record names, by the accelerometer model it fits: the
#: six-parameter autocalibration ([Song2006] eq. 10) or the nine-parameter least squares.
ALGORITHMS: Final[Mapping[Model, str]] = MappingProxyType(
    {"six": "autocal-eq10", "nine": "autocal-ls9"}
)

log = logging.getLogger(__name__)


def now() -> datetime:
    """The time stamps of captures and records (UTC)."""
    return datetime.now(UTC)


def capture_of(
    result: PoseResult,
    index: int,
    name: str,
    role: PoseRole,
    replaced: tuple[ReplacedCapture, ...],
) -> Capture:
    """The journal's capture of an accepted pose, with the captures it replaced."""
    link = result.link
    record = PoseRecord.of_window(
        result.summary,
        index=index,
        name=name,
        role=role,
        link=LinkStats(
            crc_errors=link.crc_errors,
            gaps=link.gaps,
            resyncs=link.resyncs,
            lost_samples=link.lost_samples,
        ),
        replaced=replaced,
    )
    return Capture(
        record=record,
        gyro_std=Vector3.of(result.summary.gyro_std),
        captured_at=now(),
        duration_s=result.duration_s,
        loss_fraction=result.loss_fraction,
    )


def replaced_capture(capture: Capture, reason: str) -> ReplacedCapture:
    """What is kept for audit of a capture taken again."""
    rec = capture.record
    return ReplacedCapture(
        captured_at=capture.captured_at,
        reason=reason,
        mean=rec.mean,
        std=rec.std,
        sample_count=rec.sample_count,
    )


def fit_means(captures: Mapping[int, Capture], fit_count: int) -> Array:
    """The accelerometer means of the fit poses, in order (all must be taken)."""
    return np.array([captures[i].record.mean.as_tuple() for i in range(fit_count)])


def gyro_summary(
    captures: Mapping[int, Capture], fit_count: int, solution: Solution | None
) -> GyroSummary | None:
    """Bias and noise of each gyro over the fit poses, and their bias-vs-gravity slope."""
    fit = [captures[i] for i in range(fit_count) if i in captures]
    gyro_means = [c.record.gyro_mean for c in fit]
    if not fit or any(m is None for m in gyro_means):
        return None
    means = np.array([m.as_tuple() for m in gyro_means if m is not None])
    stds = np.array([c.gyro_std.as_tuple() for c in fit])
    still = None
    if solution is not None and len(fit) == fit_count:
        gravity = apply(solution.calibration, fit_means(captures, fit_count))
        still = summarize_still_poses(means, stds, gravity)
    return GyroSummary(
        bias=Vector3.of(means.mean(axis=0)),
        noise=Vector3.of(np.sqrt((stds**2).mean(axis=0))),
        still=still,
    )


def pose_records(
    captures: Mapping[int, Capture], evidence: PoseRecord | None
) -> tuple[PoseRecord, ...]:
    """Every pose taken (plus the window that failed the unit, if not taken), in order.

    A run that ends with a pose missing (aborted after a redo) is numbered without
    the gap; the names still say which pose each one is.
    """
    taken = [captures[i].record for i in sorted(captures)]
    if evidence is not None and evidence.index not in captures:
        taken = sorted((*taken, evidence), key=lambda p: p.index)
    return tuple(
        p if p.index == i else p.model_copy(update={"index": i}) for i, p in enumerate(taken)
    )


def _temperatures(poses: list[PoseRecord]) -> Array | None:
    """The poses' temperatures, °C, when every one recorded its own (else None: the
    budget then has no temperature term)."""
    values = [p.temperature_c for p in poses]
    if any(v is None for v in values):
        return None
    return np.array(values, dtype=np.float64)


def uncertainty_record(
    captures: Mapping[int, Capture],
    fit_count: int,
    solution: Solution | None,
    gyro_fit: GyroMatrixFit | None,
    sensor: SensorSpec,
) -> UncertaintyRecord | None:
    """The expanded uncertainties of the run's coefficients
    (:mod:`station.domain.calibration.uncertainty`): the accelerometer's from the fit
    poses' means, spreads, sample counts and temperatures (drifting within ``sensor``'s
    datasheet) and the verification pose, the gyro bias's
    from the fit poses' gyro means, the gyro matrix's from its fit and the accelerometer
    calibration its moves' gravity directions came from (None: no solution)."""
    if solution is None or any(i not in captures for i in range(fit_count)):
        return None
    fit = [captures[i] for i in range(fit_count)]
    verify = captures.get(fit_count)
    budget = accelerometer_budget(
        solution,
        fit_means(captures, fit_count),
        np.array([c.record.std.as_tuple() for c in fit]),
        np.array([c.record.sample_count for c in fit]),
        verification=None if verify is None else np.array(verify.record.mean.as_tuple()),
        verification_spread=None if verify is None else np.array(verify.record.std.as_tuple()),
        verification_samples=None if verify is None else verify.record.sample_count,
        temperatures=_temperatures([c.record for c in fit]),
        verification_temperature=None if verify is None else verify.record.temperature_c,
        tempco=(sensor.offset_tempco_counts_per_c, sensor.sensitivity_tempco_per_c),
        cross_axis_bound=sensor.cross_axis,
    )
    uncertainty = Uncertainty.of_budget(budget)
    gyro_means = [c.record.gyro_mean for c in fit]
    bias = None
    if all(m is not None for m in gyro_means):
        bias = gyro_bias_uncertainty(
            np.array([m.as_tuple() for m in gyro_means if m is not None]),
            np.array([c.gyro_std.as_tuple() for c in fit]),
            np.array([c.record.sample_count for c in fit]),
            repeatability_dps=sensor.gyro_bias_repeatability_dps or 0.0,
        )
    matrix = None if gyro_fit is None else gyro_matrix_uncertainty(gyro_fit, budget)
    excluded = budget.excluded_influences
    if bias is not None and sensor.gyro_bias_repeatability_dps is None:
        excluded += ("gyro_bias_repeatability",)
    document = uncertainty.with_gyro(bias, matrix).to_dict()
    if excluded:
        document["excluded_influences"] = list(excluded)
    try:
        return UncertaintyRecord.model_validate(document)
    except ValidationError as exc:
        # An uncertainty beyond what a record holds (a non-finite one, or more than the
        # ADC's span) says the coefficients mean nothing, which the verdict's checks say
        # too; the run is recorded without it rather than lost.
        log.warning("no uncertainty recorded: %s", exc.errors()[0]["msg"])
        return None


def quality_metrics(solution: Solution, verification_error_mg: float | None) -> QualityMetrics:
    """The record's quality part, with the fit poses the solve left out as inconsistent."""
    q = solution.quality
    return QualityMetrics(
        residual_rms_mg=q.residual_rms_mg,
        residual_max_mg=q.residual_max_mg,
        condition_number=max(1.0, q.condition_number),
        verification_error_mg=verification_error_mg,
        excluded_poses=solution.excluded or None,
    )


def run_record(
    journal: RunJournal,
    settings: RunSettings,
    profile: LimitsProfile,
    solution: Solution | None,
    *,
    verdict: Verdict,
    failures: tuple[FailureReason, ...],
    disposition: Disposition | None,
    golden: bool,
    verification_error_mg: float | None,
    gyro: GyroSummary | None,
    poses: tuple[PoseRecord, ...],
    gyro_matrix: GyroMatrixRecord | None = None,
    uncertainty: UncertaintyRecord | None = None,
    check_rules: dict[str, DecisionRule] | None = None,
) -> RunRecord:
    """The record of the finished run, as it goes to the outbox: where its unit goes
    (``disposition``), whether it was the station's ``golden`` unit, the coefficients'
    ``uncertainty`` (:func:`uncertainty_record`), the profile's decision rule and the
    rule that judged each limit (``check_rules``,
    :func:`station.domain.product.judging.check_rules`) included."""
    coefficients = quality = None
    if solution is not None:
        cal = solution.calibration.to_dict()
        coefficients = Coefficients(
            offset=Vector3.model_validate(cal["offset"]),
            sensitivity=Vector3.model_validate(cal["sensitivity"]),
            matrix=tuple(tuple(row) for row in solution.calibration.matrix.tolist()),
        )
        quality = quality_metrics(solution, verification_error_mg)
    return RunRecord(
        run_id=journal.run_id,
        serial=journal.serial,
        station_id=journal.station_id,
        operator_id=journal.operator_id,
        lot=journal.lot,
        part_number=journal.part_number,
        fixture_slot=journal.fixture_slot,
        started_at=journal.started_at,
        # A wall clock stepped back during the run (NTP, a technician) must not make
        # a run that ends before it began: it ends no earlier than it started.
        finished_at=max(now(), journal.started_at),
        software_version=__version__,
        algorithm=ALGORITHMS[settings.model],
        model=settings.model,
        limits=profile.ref,
        verdict=verdict,
        disposition=disposition,
        purpose="golden" if golden else None,
        failures=failures,
        coefficients=coefficients,
        quality=quality,
        gyro=gyro,
        gyro_matrix=gyro_matrix,
        uncertainty=uncertainty,
        decision_rule=profile.rule,
        check_rules=check_rules,
        as_found=journal.as_found,
        poses=poses,
    )
