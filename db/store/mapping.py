"""Between the run record (:mod:`station.domain.record.records`) and the table rows
(:mod:`db.models`)."""

import json
from collections import defaultdict
from collections.abc import Collection
from datetime import datetime
from typing import Any

from pydantic import BaseModel
from sqlalchemy import select
from sqlalchemy.orm import Session

from db.models import Run, RunFailure, RunPose
from station.domain.record.records import (
    FailureReason,
    PoseRecord,
    RunRecord,
    RunSummary,
    StoredRun,
    Vector3,
)

#: The columns of ``runs`` that hold a field of the record as it is, under its name.
_RUN_FIELDS = (
    "run_id",
    "serial",
    "station_id",
    "operator_id",
    "lot",
    "part_number",
    "fixture_slot",
    "started_at",
    "finished_at",
    "software_version",
    "algorithm",
    "model",
    "verdict",
    "disposition",
    "purpose",
    "decision_rule",
    "check_rules",
)
#: The columns of ``runs`` that hold a field of the record's quality, under its name.
_QUALITY_FIELDS = (
    "residual_rms_mg",
    "residual_max_mg",
    "condition_number",
    "verification_error_mg",
)
#: The record's fields stored as JSON documents, each in the column of its name.
_DOCUMENT_FIELDS = ("gyro", "gyro_matrix", "as_found")
#: The fields of the record's limits, each in the column ``limits_{field}``.
_LIMITS_FIELDS = ("name", "version", "sha256")
#: The columns of ``poses`` that hold a field of the pose record (or of its link) as it is.
_POSE_FIELDS = ("index", "name", "role", "sample_count", "temperature_c")
_LINK_FIELDS = ("crc_errors", "gaps", "resyncs", "lost_samples")


def _axes_columns(prefix: str, vector: Vector3 | None) -> dict[str, float | None]:
    """The columns ``{prefix}_x``, ``_y``, ``_z`` of ``vector`` (all ``None`` without one)."""
    return {f"{prefix}_{a}": None if vector is None else getattr(vector, a) for a in "xyz"}


def _axes_of(row: Any, prefix: str) -> dict[str, float | None]:
    """The vector stored in the columns ``{prefix}_x``, ``_y``, ``_z`` of ``row``."""
    return {a: getattr(row, f"{prefix}_{a}") for a in "xyz"}


def stored_axes(row: Any, prefix: str) -> tuple[float, float, float] | None:
    """The vector in the columns ``{prefix}_x``, ``_y``, ``_z`` of ``row``; None if one is NULL."""
    x, y, z = (getattr(row, f"{prefix}_{a}") for a in "xyz")
    return None if x is None or y is None or z is None else (float(x), float(y), float(z))


def _document(field: BaseModel | None) -> Any:
    """A field of the record as its JSON column holds it."""
    return None if field is None else field.model_dump(mode="json")


def run_row(
    record: RunRecord, *, pk: int, received_at: datetime, record_sha256: str
) -> dict[str, Any]:
    """The ``runs`` row of ``record``, numbered ``pk`` in the register of runs."""
    cal, quality = record.coefficients, record.quality
    return {
        **{name: getattr(record, name) for name in _RUN_FIELDS},
        "id": pk,
        "received_at": received_at,
        **{f"limits_{name}": getattr(record.limits, name) for name in _LIMITS_FIELDS},
        **_axes_columns("offset", cal.offset if cal else None),
        **_axes_columns("sensitivity", cal.sensitivity if cal else None),
        "matrix": [list(row) for row in cal.matrix] if cal else None,
        **{name: getattr(quality, name) if quality else None for name in _QUALITY_FIELDS},
        "excluded_poses": list(quality.excluded_poses)
        if quality and quality.excluded_poses
        else None,
        **{name: _document(getattr(record, name)) for name in _DOCUMENT_FIELDS},
        "uncertainty": record.uncertainty.to_json() if record.uncertainty else None,
        "record_sha256": record_sha256,
    }


def pose_row(run_pk: int, started_at: datetime, pose: PoseRecord) -> dict[str, Any]:
    """The ``poses`` row of one pose of run ``run_pk``, started at ``started_at``."""
    return {
        "run_pk": run_pk,
        "started_at": started_at,
        **{name: getattr(pose, name) for name in _POSE_FIELDS},
        **_axes_columns("mean", pose.mean),
        **_axes_columns("std", pose.std),
        **_axes_columns("gyro", pose.gyro_mean),
        **{name: getattr(pose.link, name) for name in _LINK_FIELDS},
        "replaced": [capture.model_dump(mode="json") for capture in pose.replaced],
    }


def failure_rows(run_pk: int, record: RunRecord) -> list[dict[str, Any]]:
    """The ``run_failures`` rows of ``record``, in the order the station gave them."""
    return [
        {"run_pk": run_pk, "position": position, **failure.model_dump()}
        for position, failure in enumerate(record.failures)
    ]


def _header(run: Run, failures: list[RunFailure]) -> dict[str, Any]:
    return {
        **{
            name: getattr(run, name)
            for name in (*_RUN_FIELDS, *_DOCUMENT_FIELDS, "uncertainty", "received_at")
        },
        "limits": {name: getattr(run, f"limits_{name}") for name in _LIMITS_FIELDS},
        "failures": [failure_reason(f) for f in failures],
        "coefficients": {
            "offset": _axes_of(run, "offset"),
            "sensitivity": _axes_of(run, "sensitivity"),
            "matrix": run.matrix,
        }
        if run.offset_x is not None
        else None,
        "quality": {name: getattr(run, name) for name in (*_QUALITY_FIELDS, "excluded_poses")}
        if run.residual_rms_mg is not None
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
        **{name: getattr(pose, name) for name in _POSE_FIELDS},
        "mean": _axes_of(pose, "mean"),
        "std": _axes_of(pose, "std"),
        "gyro_mean": _axes_of(pose, "gyro") if pose.gyro_x is not None else None,
        "link": {name: getattr(pose, name) for name in _LINK_FIELDS},
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
