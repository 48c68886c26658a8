"""``calstation solve LOG.csv --stream`` calibrates what the recording supports and says
what it cannot: K not determined (with the reason, exit 0) beside the accelerometer and
the gyro bias; a still window fitted to the recording's own rests."""

import gzip
import json
from pathlib import Path

import numpy as np
import pytest

from station.simulator.recording import (
    StreamPlan,
    k_in_calibrated_frame,
    pose_orientations,
    random_imu,
    recorded_stream,
    spread_directions,
)
from station.simulator.sensor import SensorTruth
from tests.conftest import REPO_ROOT, CliRunner

HEADER = "t,ax,ay,az,gx,gy,gz"
FERRARIS = REPO_ROOT / "tests" / "data" / "imucal" / "example_ferraris_session.csv.gz"


def _recording(
    tmp_path: Path, seed: int, poses: int, plan: StreamPlan, cross_axis: float = 0.02
) -> tuple[SensorTruth, Path]:
    rng = np.random.default_rng(seed)
    imu = random_imu(rng, cross_axis=cross_axis)
    stream = recorded_stream(rng, imu, pose_orientations(rng, spread_directions(poses)), plan)
    path = tmp_path / f"log{seed}.csv"
    rows = np.column_stack([stream.t, stream.accel_counts, stream.gyro_dps])
    np.savetxt(path, rows, delimiter=",", header=HEADER, comments="", fmt="%.10g")
    return imu, path


def _xyz(values: object) -> np.ndarray:
    assert isinstance(values, dict)
    return np.array([values[a] for a in "xyz"])


def test_too_few_moves_for_k_still_give_the_accelerometer_and_the_gyro_bias(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    # Six poses: the six-parameter accelerometer is determined, K (six moves) is not.
    imu, path = _recording(tmp_path, 3, 6, StreamPlan(rate_hz=200.0), cross_axis=0.0)
    result = call_cli("solve", str(path), "--stream", "--json")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    gyro, u = data["gyro"], data["uncertainty"]
    assert gyro["scale_matrix"] is None
    assert gyro["not_determined"] == "gyro matrix needs 6 usable moves, got 5 of 5"
    assert "gyro_matrix" not in u
    assert (np.abs(_xyz(data["offset"]) - imu.offset_counts) <= _xyz(u["offset"])).all()
    sensitivity_error = np.abs(_xyz(data["sensitivity"]) - imu.sensitivity_counts_per_g)
    assert (sensitivity_error <= _xyz(u["sensitivity"])).all()
    bias_error = np.abs(np.array(gyro["bias_dps"]) - imu.gyro_bias_dps)
    assert (bias_error <= np.array(u["gyro_bias_dps"])).all()
    text = call_cli("solve", str(path), "--stream")
    assert text.returncode == 0
    assert "gyro K not determined: gyro matrix needs 6 usable moves, got 5 of 5" in text.stdout


def test_rests_shorter_than_the_default_window_are_found_by_the_fitted_one(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    # Rests of 0.8 s: a 1 s window finds none of them; the window fitted to the rests
    # (half the shortest, at least 0.5 s) finds all twelve, and K holds its truth.
    imu, path = _recording(tmp_path, 7, 12, StreamPlan(rate_hz=200.0, still_s=0.8, move_s=1.0))
    fixed = call_cli("solve", str(path), "--stream", "--model", "nine", "--still-window", "1")
    assert fixed.returncode == 2
    assert "still poses found, the nine-parameter model needs 9" in fixed.stderr
    result = call_cli("solve", str(path), "--stream", "--model", "nine", "--json")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["poses"] == 12
    assert data["still_window_s"] == pytest.approx(0.5)
    k = np.array(data["gyro"]["scale_matrix"])
    u = np.array(data["uncertainty"]["gyro_matrix"])
    assert (np.abs(k - k_in_calibrated_frame(imu, "nine")) <= u).all()


@pytest.fixture(scope="module")
def ferraris_stream(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """imucal's public session under the station's column names (``t``: sample number)."""
    path = tmp_path_factory.mktemp("imucal") / "ferraris.csv"
    with gzip.open(FERRARIS, "rt") as src:
        header = src.readline().strip().split(",")
        table = np.loadtxt(src, delimiter=",")
    columns = ("n_samples", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")
    np.savetxt(
        path,
        table[:, [header.index(c) for c in columns]],
        delimiter=",",
        header=HEADER,
        comments="",
        fmt="%.17g",
    )
    return path


def _ferraris(call_cli: CliRunner, path: Path, *options: str) -> dict[str, object]:
    result = call_cli(
        "solve",
        str(path),
        "--stream",
        "--accel-units",
        "m/s2",
        "--rate",
        "102.4",
        "--json",
        *options,
    )
    assert result.returncode == 0, result.stderr
    data: dict[str, object] = json.loads(result.stdout)
    return data


def test_the_public_sessions_rests_keep_the_default_second(
    call_cli: CliRunner, ferraris_stream: Path
) -> None:
    # Its rests last 2.6–9.5 s: the fitted window is the default one, and so are the
    # figures docs/benchmarks.md reproduces.
    fitted = _ferraris(call_cli, ferraris_stream)
    default = _ferraris(call_cli, ferraris_stream, "--still-window", "1")
    assert fitted["still_window_s"] == default["still_window_s"]
    assert fitted["poses"] == default["poses"] == 13
    assert fitted["offset"] == default["offset"]
    assert fitted["gyro"] == default["gyro"]


def test_declared_turns_the_moves_contradict_leave_k_not_determined(
    call_cli: CliRunner, ferraris_stream: Path
) -> None:
    # Turns declared 440° where the session's sweep 360°: within the 25 % that finds a
    # turn, but K fitted to them misses the moves by more than K = I does. No K is
    # printed; the accelerometer and the gyro bias are the session's all the same.
    plain = _ferraris(call_cli, ferraris_stream)
    data = _ferraris(call_cli, ferraris_stream, "--known-turn-deg", "440")
    gyro = data["gyro"]
    assert isinstance(gyro, dict)
    assert gyro["scale_matrix"] is None
    assert "more than without it" in gyro["not_determined"]
    assert data["offset"] == plain["offset"]
    plain_gyro = plain["gyro"]
    assert isinstance(plain_gyro, dict)
    assert gyro["bias_dps"] == plain_gyro["bias_dps"]
