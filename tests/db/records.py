"""Run records for tests, built from a known calibration so every number is consistent."""

import uuid
from datetime import UTC, datetime, timedelta
from typing import Any

import numpy as np

from station.domain.product.limits import load_profile
from station.domain.record.records import RunRecord
from station.domain.sensors.sensor import NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G

#: Gravity directions of the six fit poses and one verification pose (unit vectors).
DIRECTIONS = np.array(
    [
        [0.05, 0.02, 0.998],
        [0.03, -0.04, -0.998],
        [0.997, 0.06, 0.04],
        [-0.998, 0.03, -0.05],
        [0.04, 0.997, -0.06],
        [-0.02, -0.998, 0.05],
        [0.577, 0.577, 0.577],
    ]
)
DIRECTIONS /= np.linalg.norm(DIRECTIONS, axis=1, keepdims=True)
POSE_NAMES = ("z_up", "z_down", "x_up", "x_down", "y_up", "y_down", "verify")
#: The shipped limits profile, as a station sends it: the reference and the profile.
LIMITS = load_profile().ref.model_dump(mode="json")
T0 = datetime(2026, 11, 2, 8, 0, tzinfo=UTC)
#: How long each run of :func:`make_record` lasts, and its poses.
RUN_SECONDS = 95.0
POSES_PER_RUN = len(POSE_NAMES)


def make_record(
    *,
    serial: str = "PT-000001",
    station_id: str = "line1-st1",
    verdict: str = "pass",
    started_at: datetime = T0,
    offset: tuple[float, float, float] = (2081.9, 2041.2, 1960.5),
    sensitivity: tuple[float, float, float] = (813.95, 815.66, 820.17),
    run_id: uuid.UUID | None = None,
    **overrides: Any,
) -> RunRecord:
    """A complete run whose poses are exactly what ``offset``/``sensitivity`` predict."""
    offset_a, sens_a = np.array(offset), np.array(sensitivity)
    means = offset_a + sens_a * DIRECTIONS
    poses = [
        {
            "index": i,
            "name": POSE_NAMES[i],
            "role": "verify" if i == 6 else "fit",
            "mean": dict(zip("xyz", means[i].tolist(), strict=True)),
            "std": {"x": 1.1, "y": 1.2, "z": 1.3},
            "sample_count": 1024,
            "gyro_mean": {"x": 0.01, "y": -0.02, "z": 0.005},
            "temperature_c": 24.5,
            "link": {"crc_errors": i % 2, "gaps": 0, "resyncs": 0, "lost_samples": 0},
            "replaced": [
                {
                    "captured_at": (started_at + timedelta(seconds=5)).isoformat(),
                    "reason": "moved during capture",
                    "mean": {"x": NOMINAL_OFFSET_COUNTS, "y": 2050.0, "z": 2900.0},
                    "std": {"x": 40.0, "y": 35.0, "z": 50.0},
                    "sample_count": 1024,
                }
            ]
            if i == 0
            else [],
        }
        for i in range(len(DIRECTIONS))
    ]
    failures = (
        []
        if verdict == "pass"
        else [
            {
                "code": "sensitivity_out_of_range",
                "message": "sensitivity z 820.17 counts/g above 819.0",
                "measured": sensitivity[2],
                "lower": NOMINAL_SENSITIVITY_COUNTS_PER_G * 0.95,
                "upper": 819.0,
                "axis": "z",
            }
        ]
    )
    payload: dict[str, Any] = {
        "run_id": str(run_id or uuid.uuid4()),
        "serial": serial,
        "station_id": station_id,
        "operator_id": "op-17",
        "started_at": started_at.isoformat(),
        "finished_at": (started_at + timedelta(seconds=RUN_SECONDS)).isoformat(),
        "software_version": "1.4.0",
        "algorithm": "autocal-ls",
        "model": "six",
        "limits": LIMITS,
        "verdict": verdict,
        "failures": failures,
        "coefficients": {
            "offset": dict(zip("xyz", offset, strict=True)),
            "sensitivity": dict(zip("xyz", sensitivity, strict=True)),
            "matrix": np.diag(1.0 / sens_a).tolist(),
        },
        "quality": {
            "residual_rms_mg": 0.4,
            "residual_max_mg": 0.9,
            "condition_number": 3.2,
            "verification_error_mg": 0.7,
        },
        "gyro": {
            "bias": {"x": 0.01, "y": -0.02, "z": 0.005},
            "noise": {"x": 0.05, "y": 0.05, "z": 0.06},
        },
        "poses": poses,
    }
    payload.update(overrides)
    return RunRecord.model_validate(payload)


def _failed(code: str, **more: Any) -> dict[str, Any]:
    return {"verdict": "fail", "failures": [{"code": code, "message": "out of limits"}], **more}


#: What a run can be for its unit: it wrote the unit or not, it counts or not.
OUTCOMES: dict[str, dict[str, Any]] = {
    "pass": {},
    "fail, written": _failed("sensitivity_out_of_range"),
    "fail, no coefficients": _failed("calibration", coefficients=None, quality=None),
    "write-back failed": _failed("writeback"),
    "saturated": _failed("saturated", coefficients=None, quality=None),
    "aborted": _failed("aborted", coefficients=None, quality=None, gyro=None),
}
