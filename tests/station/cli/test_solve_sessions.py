"""``calstation solve A.csv B.csv ... --stream``: power-on sessions of one unit, its gyro
bias' turn-on to turn-on repeatability measured across them and put in each session's U
in place of a declared figure (``docs/calibration.md``, "Uncertainty budget")."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import chi2

from station.simulator.recording import (
    StreamPlan,
    pose_orientations,
    random_imu,
    recorded_stream,
    spread_directions,
)
from tests.conftest import CliRunner

HEADER = "t,ax,ay,az,gx,gy,gz"
#: The simulated unit's bias moves by this much (1 σ, deg/s) from one power-on to the next.
TURN_ON_DPS = 0.05
SESSIONS = 6


@pytest.fixture(scope="module")
def sessions(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Six recordings of one simulated unit, its gyro bias drawn afresh at each power-on."""
    rng = np.random.default_rng(47)
    unit = random_imu(rng, cross_axis=0.0)
    plan = StreamPlan(rate_hz=200.0, still_s=1.5, move_s=1.0)
    into = tmp_path_factory.mktemp("sessions")
    paths = []
    for session in range(SESSIONS):
        powered = replace(unit, gyro_bias_dps=unit.gyro_bias_dps + rng.normal(0.0, TURN_ON_DPS, 3))
        orientations = pose_orientations(rng, spread_directions(12))
        stream = recorded_stream(rng, powered, orientations, plan)
        rows = np.column_stack([stream.t, stream.accel_counts, stream.gyro_dps])
        path = into / f"session{session}.csv"
        np.savetxt(path, rows, delimiter=",", header=HEADER, comments="", fmt="%.17g")
        paths.append(path)
    return paths


def _json(call_cli: CliRunner, *args: str) -> dict[str, object]:
    result = call_cli("solve", *args, "--stream", "--model", "nine", "--json")
    assert result.returncode == 0, result.stderr
    data: dict[str, object] = json.loads(result.stdout)
    return data


def test_the_sessions_measure_the_bias_repeatability_and_each_u_holds_it(
    call_cli: CliRunner, sessions: list[Path]
) -> None:
    data = _json(call_cli, *map(str, sessions))
    measured = data["gyro_bias_repeatability"]
    assert isinstance(measured, dict)
    assert (measured["sessions"], measured["degrees_of_freedom"]) == (SESSIONS, SESSIONS - 1)
    assert measured["unit"] == "deg/s"
    payloads = data["sessions"]
    assert isinstance(payloads, list)
    biases = np.array([p["gyro"]["bias_dps"] for p in payloads])
    np.testing.assert_allclose(measured["biases"], biases, rtol=1e-12)
    value = np.array(measured["value"])
    np.testing.assert_allclose(value, np.std(biases, axis=0, ddof=1), rtol=1e-12)
    # The sessions' spread is the turn-on spread (each session's own noise is ~0.001
    # deg/s): within the 99 % χ² interval of a standard deviation of 5 degrees of freedom.
    dof = SESSIONS - 1
    low, high = (TURN_ON_DPS * np.sqrt(chi2.ppf(q, dof) / dof) for q in (0.005, 0.995))
    assert ((low <= value) & (value <= high)).all(), value
    # Each session's U: its own (one recording alone) and the measured figure in quadrature.
    alone = _json(call_cli, str(sessions[0]))
    u_alone = np.array(alone["uncertainty"]["gyro_bias_dps"])  # type: ignore[index]
    first = payloads[0]
    assert first["file"] == str(sessions[0])
    u_first = np.array(first["uncertainty"]["gyro_bias_dps"])
    np.testing.assert_allclose(u_first**2, u_alone**2 + (2.0 * value) ** 2, rtol=1e-9)
    assert "gyro_bias_repeatability" not in [e["influence"] for e in first["excluded_influences"]]
    assert "gyro_bias_repeatability" in [
        e["influence"]
        for e in alone["excluded_influences"]  # type: ignore[attr-defined]
    ]


def test_the_screen_names_the_measured_repeatability(
    call_cli: CliRunner, sessions: list[Path]
) -> None:
    result = call_cli("solve", *map(str, sessions[:3]), "--stream", "--model", "nine")
    assert result.returncode == 0, result.stderr
    last = result.stdout.strip().splitlines()[-1]
    assert last.startswith("gyro bias repeatability measured across 3 sessions (2 degrees")
    assert "NOT IN U: gyro_bias_repeatability" not in result.stdout


def test_a_declared_repeatability_with_several_sessions_is_refused(
    call_cli: CliRunner, sessions: list[Path]
) -> None:
    result = call_cli(
        "solve", *map(str, sessions[:2]), "--stream", "--gyro-bias-repeatability", "0.05"
    )
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [
        "calstation: error: --gyro-bias-repeatability: declared, but 2 sessions measure it: "
        "leave it out, or give one recording"
    ]


def test_several_pose_files_are_refused(call_cli: CliRunner, tmp_path: Path) -> None:
    poses = tmp_path / "poses.csv"
    poses.write_text("ax,ay,az\n2031,1999,1143\n", encoding="utf-8")
    result = call_cli("solve", str(poses), str(poses))
    assert result.returncode == 2
    assert "use them with --stream" in result.stderr
    assert "Traceback" not in result.stderr
