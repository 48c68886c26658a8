"""The run record's physical bounds: every record the station can compute validates,
absurd finite values (1e300) anywhere are refused with the field named."""

from typing import Any

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from pydantic import ValidationError

from station.domain.calibration import CalibrationError, apply, solve
from station.domain.gyro.still import summarize_still_poses
from station.domain.record.records import (
    Coefficients,
    GyroSummary,
    QualityMetrics,
    RunRecord,
    Vector3,
)
from station.domain.sensors.record_bounds import ERROR_MAX_MG, GYRO_RANGE_DPS
from station.simulator.recording import pose_means, six_directions
from station.simulator.sensor import SensorTruth
from tests.conftest import examples
from tests.db.records import make_record


def _vec(values: np.ndarray) -> Vector3:
    return Vector3(x=float(values[0]), y=float(values[1]), z=float(values[2]))


@settings(max_examples=examples(60), deadline=None)
@given(
    offset=st.lists(st.floats(600, 3500), min_size=3, max_size=3),
    sensitivity=st.lists(st.floats(100, 1500), min_size=3, max_size=3),
    coupling=st.lists(st.floats(-0.2, 0.2), min_size=9, max_size=9),
    tilt=st.floats(0, 20),
    noise=st.floats(0, 50),
    gyro_bias=st.lists(st.floats(-GYRO_RANGE_DPS, GYRO_RANGE_DPS), min_size=3, max_size=3),
    seed=st.integers(0, 2**32 - 1),
)
def test_whatever_the_station_computes_from_in_range_counts_validates(
    offset: list[float],
    sensitivity: list[float],
    coupling: list[float],
    tilt: float,
    noise: float,
    gyro_bias: list[float],
    seed: int,
) -> None:
    """Any unit whose poses read within the ADC (clipped at the rails as the ADC does):
    the coefficients, quality and gyro figures the station would record are in bounds."""
    rng = np.random.default_rng(seed)
    cross = np.array(coupling).reshape(3, 3)
    np.fill_diagonal(cross, 0.0)
    unit = SensorTruth.accelerometer(np.array(offset), np.diag(sensitivity) @ (np.eye(3) + cross))
    poses = np.clip(pose_means(unit, six_directions(rng, tilt), noise, rng), 0, 4095)
    verify = np.clip(unit.still_counts(np.array([[0.577, 0.577, 0.577]]))[0], 0, 4095)
    try:
        solution = solve(poses)
    except CalibrationError:
        assume(False)  # the station records a failure without coefficients
    cal = solution.calibration.to_dict()
    Coefficients(
        offset=Vector3.model_validate(cal["offset"]),
        sensitivity=Vector3.model_validate(cal["sensitivity"]),
        matrix=tuple(tuple(row) for row in solution.calibration.matrix.tolist()),
    )
    error = abs(float(np.linalg.norm(apply(solution.calibration, verify))) - 1.0) * 1000.0
    assert error <= ERROR_MAX_MG
    QualityMetrics(
        residual_rms_mg=solution.quality.residual_rms_mg,
        residual_max_mg=solution.quality.residual_max_mg,
        condition_number=max(1.0, solution.quality.condition_number),
        verification_error_mg=error,
    )
    means = np.clip(np.array(gyro_bias) + rng.normal(0, 0.1, (6, 3)), -655.36, 655.34)
    stds = np.abs(rng.normal(0, 300, (6, 3)))
    still = summarize_still_poses(means, stds, apply(solution.calibration, poses))
    GyroSummary(
        bias=_vec(means.mean(axis=0)), noise=_vec(np.sqrt((stds**2).mean(axis=0))), still=still
    )


def _set(body: dict[str, Any], path: str, value: object) -> None:
    keys = [int(k) if k.isdigit() else k for k in path.split(".")]
    for key in keys[:-1]:
        body = body[key]  # type: ignore[index]
    body[keys[-1]] = value  # type: ignore[index]


ABSURD = [
    ("poses.0.mean.x", 1e300),
    ("poses.0.std.x", 1e300),
    ("poses.0.std.y", -1.0),
    ("poses.0.gyro_mean.z", 1e300),
    ("poses.0.temperature_c", 1e300),
    ("poses.0.sample_count", 2**40),
    ("poses.0.link.crc_errors", -1),
    ("poses.0.replaced.0.std.x", 1e300),
    ("gyro.bias.x", 1e300),
    ("gyro.noise.y", 1e300),
    ("gyro.noise.y", -0.1),
    ("coefficients.offset.x", 1e300),
    ("coefficients.sensitivity.y", 0.0),
    ("coefficients.sensitivity.y", 1e300),
    ("coefficients.matrix.1.1", 1e300),
    ("quality.residual_rms_mg", 1e300),
    ("quality.condition_number", 1e300),
    ("quality.verification_error_mg", 1e300),
    ("finished_at", "2027-11-02T08:00:00Z"),
]


@pytest.mark.parametrize(("path", "value"), ABSURD)
def test_absurd_values_are_refused_naming_the_field(path: str, value: object) -> None:
    body = make_record().model_dump(mode="json")
    body["gyro"] = {"bias": {"x": 0.1, "y": 0.0, "z": -0.1}, "noise": {"x": 1, "y": 1, "z": 1}}
    RunRecord.model_validate(body)  # valid before the change
    _set(body, path, value)
    with pytest.raises(ValidationError) as refused:
        RunRecord.model_validate(body)
    error = refused.value.errors()[0]
    where = ".".join(str(part) for part in error["loc"])
    field = path.rsplit(".", 1)
    named = f"{where} {error['msg']}"
    assert field[0].split(".")[0] in named or path == "finished_at", named
    assert field[-1] in named, named


@pytest.mark.parametrize(
    ("path", "value"),
    [
        ("axes.0.bias_dps", 1e300),
        ("axes.0.slope_p_value", 2.0),
        ("axes.0.slope_dps_per_g", [1e300, 0.0, 0.0]),
        ("axes.0.reason", "a\x00b"),
        ("alpha", float("nan")),
    ],
)
def test_the_still_summary_is_bounded_too(path: str, value: object) -> None:
    still = summarize_still_poses(
        np.full((6, 3), 0.1), np.full((6, 3), 0.08), six_directions()
    ).model_dump(mode="json")
    body = make_record().model_dump(mode="json")
    body["gyro"] = {"bias": {"x": 0.1, "y": 0.1, "z": 0.1}, "noise": {"x": 1, "y": 1, "z": 1}}
    body["gyro"]["still"] = still
    RunRecord.model_validate(body)
    _set(still, path, value)
    with pytest.raises(ValidationError, match=path.rsplit(".", 1)[-1]):
        RunRecord.model_validate(body)
