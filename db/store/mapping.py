"""Between the run record (:mod:`station.domain.record.records`) and the table rows
(:mod:`db.models`)."""

import json
from collections import defaultdict
from collections.abc import Collection
from datetime import datetime
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from db.models import Run, RunFailure, RunPose
from station.domain.record.records import (
    FailureReason,
    PoseRecord,
    RunRecord,
    RunSummary,
    StoredRun,
)


def run_row(
    record: RunRecord, *, pk: int, received_at: datetime, record_sha256: str
) -> dict[str, Any]:
    """The ``runs`` row of ``record``, numbered ``pk`` in the register of runs."""
    cal, quality = record.coefficients, record.quality
    return {
        "id": pk,
        "run_id": record.run_id,
        "serial": record.serial,
        "station_id": record.station_id,
        "operator_id": record.operator_id,
        "lot": record.lot,
        "part_number": record.part_number,
        "fixture_slot": record.fixture_slot,
        "started_at": record.started_at,
        "finished_at": record.finished_at,
        "received_at": received_at,
        "software_version": record.software_version,
        "algorithm": record.algorithm,
        "model": record.model,
        "limits_name": record.limits.name,
        "limits_version": record.limits.version,
        "limits_sha256": record.limits.sha256,
        "verdict": record.verdict,
        "disposition": record.disposition,
        "purpose": record.purpose,
        "offset_x": cal.offset.x if cal else None,
        "offset_y": cal.offset.y if cal else None,
        "offset_z": cal.offset.z if cal else None,
        "sensitivity_x": cal.sensitivity.x if cal else None,
        "sensitivity_y": cal.sensitivity.y if cal else None,
        "sensitivity_z": cal.sensitivity.z if cal else None,
        "matrix": [list(row) for row in cal.matrix] if cal else None,
        "residual_rms_mg": quality.residual_rms_mg if quality else None,
        "residual_max_mg": quality.residual_max_mg if quality else None,
        "condition_number": quality.condition_number if quality else None,
        "verification_error_mg": quality.verification_error_mg if quality else None,
        "excluded_poses": list(quality.excluded_poses)
        if quality and quality.excluded_poses
        else None,
        "gyro": record.gyro.model_dump(mode="json") if record.gyro else None,
        "gyro_matrix": record.gyro_matrix.model_dump(mode="json") if record.gyro_matrix else None,
        "uncertainty": record.uncertainty.to_json() if record.uncertainty else None,
        "decision_rule": record.decision_rule,
        "check_rules": record.check_rules,
        "as_found": record.as_found.model_dump(mode="json") if record.as_found else None,
        "record_sha256": record_sha256,
    }


def pose_row(run_pk: int, started_at: datetime, pose: PoseRecord) -> dict[str, Any]:
    """The ``poses`` row of one pose of run ``run_pk``, started at ``started_at``."""
    gyro = pose.gyro_mean
    return {
        "run_pk": run_pk,
        "started_at": started_at,
        "index": pose.index,
        "name": pose.name,
        "role": pose.role,
        "mean_x": pose.mean.x,
        "mean_y": pose.mean.y,
        "mean_z": pose.mean.z,
        "std_x": pose.std.x,
        "std_y": pose.std.y,
        "std_z": pose.std.z,
        "sample_count": pose.sample_count,
        "gyro_x": gyro.x if gyro else None,
        "gyro_y": gyro.y if gyro else None,
        "gyro_z": gyro.z if gyro else None,
        "temperature_c": pose.temperature_c,
        "crc_errors": pose.link.crc_errors,
        "gaps": pose.link.gaps,
        "resyncs": pose.link.resyncs,
        "lost_samples": pose.link.lost_samples,
        "replaced": [capture.model_dump(mode="json") for capture in pose.replaced],
    }


def failure_rows(run_pk: int, record: RunRecord) -> list[dict[str, Any]]:
    """The ``run_failures`` rows of ``record``, in the order the station gave them."""
    return [
        {"run_pk": run_pk, "position": position, **failure.model_dump()}
        for position, failure in enumerate(record.failures)
    ]


def _header(run: Run, failures: list[RunFailure]) -> dict[str, Any]:
    has_cal = run.offset_x is not None
    has_quality = run.residual_rms_mg is not None
    return {
        "run_id": run.run_id,
        "serial": run.serial,
        "station_id": run.station_id,
        "operator_id": run.operator_id,
        "lot": run.lot,
        "part_number": run.part_number,
        "fixture_slot": run.fixture_slot,
        "started_at": run.started_at,
        "finished_at": run.finished_at,
        "received_at": run.received_at,
        "software_version": run.software_version,
        "algorithm": run.algorithm,
        "model": run.model,
        "limits": {
            "name": run.limits_name,
            "version": run.limits_version,
            "sha256": run.limits_sha256,
        },
        "verdict": run.verdict,
        "disposition": run.disposition,
        "purpose": run.purpose,
        "gyro": run.gyro,
        "gyro_matrix": run.gyro_matrix,
        "uncertainty": run.uncertainty,
        "decision_rule": run.decision_rule,
        "check_rules": run.check_rules,
        "as_found": run.as_found,
        "failures": [failure_reason(f) for f in failures],
        "coefficients": {
            "offset": {"x": run.offset_x, "y": run.offset_y, "z": run.offset_z},
            "sensitivity": {
                "x": run.sensitivity_x,
                "y": run.sensitivity_y,
                "z": run.sensitivity_z,
            },
            "matrix": run.matrix,
        }
        if has_cal
        else None,
        "quality": {
            "residual_rms_mg": run.residual_rms_mg,
            "residual_max_mg": run.residual_max_mg,
            "condition_number": run.condition_number,
            "verification_error_mg": run.verification_error_mg,
            "excluded_poses": run.excluded_poses,
        }
        if has_quality
        else None,
    }


def failures_of(session: Session, pks: Collection[int]) -> dict[int, list[RunFailure]]:
    """The stored failures of the runs ``pks``, per run in their order."""
    by_run: dict[int, list[RunFailure]] = defaultdict(list)
    if pks:
        for failure in session.scalars(
            select(RunFailure)
            .where(RunFailure.run_pk.in_(pks))
            .order_by(RunFailure.run_pk, RunFailure.position)
        ):
            by_run[failure.run_pk].append(failure)
    return by_run


def failure_reason(failure: RunFailure) -> FailureReason:
    """A stored failure as the record's reason."""
    return FailureReason.model_validate(failure, from_attributes=True)


def summary_of(run: Run, failures: list[RunFailure]) -> RunSummary:
    """The stored run ``run`` without its poses."""
    return RunSummary.model_validate(_header(run, failures))


def _pose(pose: RunPose) -> dict[str, Any]:
    return {
        "index": pose.index,
        "name": pose.name,
        "role": pose.role,
        "mean": {"x": pose.mean_x, "y": pose.mean_y, "z": pose.mean_z},
        "std": {"x": pose.std_x, "y": pose.std_y, "z": pose.std_z},
        "sample_count": pose.sample_count,
        "gyro_mean": {"x": pose.gyro_x, "y": pose.gyro_y, "z": pose.gyro_z}
        if pose.gyro_x is not None
        else None,
        "temperature_c": pose.temperature_c,
        "link": {
            "crc_errors": pose.crc_errors,
            "gaps": pose.gaps,
            "resyncs": pose.resyncs,
            "lost_samples": pose.lost_samples,
        },
        "replaced": pose.replaced,
    }


def stored_run_of(
    run: Run, failures: list[RunFailure], poses: list[RunPose], profile: str | None = None
) -> StoredRun:
    """The stored run ``run`` with every pose and its stored limits ``profile`` (JSON)."""
    header = _header(run, failures)
    if profile is not None:
        header["limits"]["profile"] = json.loads(profile)
    return StoredRun.model_validate({**header, "poses": [_pose(p) for p in poses]})
