"""``calstation solve``: results in the units the readings were declared in.

A recording (or pose file) declared in g answers offsets in g and sensitivities as a
dimensionless scale factor, in m/s² offsets in m/s²; U in the same units; the putter's
counts only for counts (docs/calibration.md, "Results in the declared units").
"""

import gzip
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from station.simulator.recording import (
    StreamPlan,
    pose_orientations,
    random_imu,
    recorded_stream,
    spread_directions,
)
from tests.conftest import REPO_ROOT, CliRunner

G0 = 9.80665
ZERO, PER_G = 2048.0, 819.2
HEADER = "t,ax,ay,az,gx,gy,gz"
#: imucal's example Ferraris session (mad-lab-fau/imucal, MIT, tests/data/imucal/README.md).
FERRARIS = REPO_ROOT / "tests" / "data" / "imucal" / "example_ferraris_session.csv.gz"
FERRARIS_RATE_HZ = 102.4


def _xyz(values: object) -> np.ndarray:
    assert isinstance(values, dict)
    return np.array([values[a] for a in "xyz"])


def _solved(call_cli: CliRunner, path: Path, *options: str) -> dict[str, object]:
    result = call_cli("solve", str(path), "--json", *options)
    assert result.returncode == 0, result.stderr
    data: dict[str, object] = json.loads(result.stdout)
    return data


@pytest.fixture(scope="module")
def uncoupled_recording() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A simulated unit without cross-axis coupling (the six-parameter model is exact for
    it): its recording in counts, its true offsets (counts) and sensitivities (counts/g)."""
    rng = np.random.default_rng(43)
    imu = random_imu(rng, cross_axis=0.0)
    plan = StreamPlan(rate_hz=200.0, still_s=1.5, move_s=1.0)
    stream = recorded_stream(rng, imu, pose_orientations(rng, spread_directions(12)), plan)
    rows = np.column_stack([stream.t, stream.accel_counts, stream.gyro_dps])
    return rows, imu.offset_counts, imu.sensitivity_counts_per_g


@pytest.mark.parametrize(("unit", "per_g"), [("g", 1.0), ("m/s2", G0)])
def test_a_stream_declared_in_g_or_m_s2_answers_in_it_with_the_truth_within_u(
    call_cli: CliRunner,
    tmp_path: Path,
    uncoupled_recording: tuple[np.ndarray, np.ndarray, np.ndarray],
    unit: str,
    per_g: float,
) -> None:
    rows, offset_counts, sensitivity_counts = uncoupled_recording
    declared = rows.copy()
    declared[:, 1:4] = (rows[:, 1:4] - ZERO) / PER_G * per_g
    path = tmp_path / "log.csv"
    np.savetxt(path, declared, delimiter=",", header=HEADER, comments="", fmt="%.10g")
    data = _solved(call_cli, path, "--stream", "--accel-units", unit)
    assert data["units"] == {
        "offset": unit,
        "sensitivity": "1 (scale factor)",
        "residual": unit,
        "gyro_bias": "deg/s",
        "gyro_matrix": "1",
    }
    true_offset = (offset_counts - ZERO) / PER_G * per_g
    true_scale = sensitivity_counts / PER_G
    u = data["uncertainty"]
    assert isinstance(u, dict)
    offset, scale = _xyz(data["offset"]), _xyz(data["sensitivity"])
    assert (np.abs(offset - true_offset) <= _xyz(u["offset"])).all(), (offset, true_offset)
    assert (np.abs(scale - true_scale) <= _xyz(u["sensitivity"])).all(), (scale, true_scale)
    # A scale factor near 1, an offset of a few hundredths of g: no count in sight.
    assert (np.abs(scale - 1.0) < 0.1).all()
    assert (np.abs(offset) < 0.3 * per_g).all()
    assert "residual_limit_counts" not in data
    assert data["residual_limit"] == pytest.approx(2.0 / PER_G * per_g)
    text = call_cli("solve", str(path), "--stream", "--accel-units", unit).stdout
    assert f"offset ({unit})" in text
    assert "sensitivity (scale factor)" in text
    assert "counts" not in text


def test_the_putters_counts_still_answer_in_counts(
    call_cli: CliRunner,
    tmp_path: Path,
    uncoupled_recording: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:
    rows, offset_counts, sensitivity_counts = uncoupled_recording
    path = tmp_path / "counts.csv"
    np.savetxt(path, rows, delimiter=",", header=HEADER, comments="", fmt="%.10g")
    data = _solved(call_cli, path, "--stream")
    assert data["units"] == {
        "offset": "counts",
        "sensitivity": "counts/g",
        "residual": "counts",
        "gyro_bias": "deg/s",
        "gyro_matrix": "1",
    }
    u = data["uncertainty"]
    assert isinstance(u, dict)
    assert (np.abs(_xyz(data["offset"]) - offset_counts) <= _xyz(u["offset"])).all()
    assert (np.abs(_xyz(data["sensitivity"]) - sensitivity_counts) <= _xyz(u["sensitivity"])).all()
    assert data["residual_limit_counts"] == 2.0


unit_and_gravity = st.sampled_from([("g", 1.0), ("m/s2", G0)])


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    declared=unit_and_gravity,
    offset_g=st.lists(st.floats(-0.2, 0.2), min_size=3, max_size=3),
    scale=st.lists(st.floats(0.9, 1.1), min_size=3, max_size=3),
    poses=st.integers(8, 20),
)
def test_a_pose_file_in_g_or_m_s2_gives_back_its_offsets_and_scales(
    call_cli: CliRunner,
    tmp_path_factory: pytest.TempPathFactory,
    declared: tuple[str, float],
    offset_g: list[float],
    scale: list[float],
    poses: int,
) -> None:
    # Noise-free means of an uncoupled axis triad, reading = scale·g + offset: the fit is
    # exact, so the declared-unit answer is the truth in that unit to rounding.
    unit, per_g = declared
    means = (np.array(offset_g) + spread_directions(poses) * np.array(scale)) * per_g
    path = tmp_path_factory.mktemp("poses") / "poses.csv"
    np.savetxt(path, means, delimiter=",", header="ax,ay,az", comments="", fmt="%.15g")
    data = _solved(call_cli, path, "--accel-units", unit)
    assert data["units"] == {"offset": unit, "sensitivity": "1 (scale factor)", "residual": unit}
    np.testing.assert_allclose(_xyz(data["offset"]), np.array(offset_g) * per_g, atol=1e-9)
    np.testing.assert_allclose(_xyz(data["sensitivity"]), scale, rtol=1e-9)


def test_a_pose_files_spreads_are_read_in_its_declared_unit(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    # The same poses and spreads in counts and in g: the same U, restated in g.
    rng = np.random.default_rng(5)
    counts = ZERO + spread_directions(10) * PER_G * 1.01 + rng.normal(0.0, 0.2, (10, 3))
    spread_counts = np.full((10, 3), 3.0)
    header = "ax,ay,az,sx,sy,sz,n"
    in_counts, in_g = tmp_path / "counts.csv", tmp_path / "g.csv"
    n = np.full((10, 1), 256)
    np.savetxt(
        in_counts,
        np.hstack([counts, spread_counts, n]),
        delimiter=",",
        header=header,
        comments="",
        fmt="%.15g",
    )
    g_table = np.hstack([(counts - ZERO) / PER_G, spread_counts / PER_G, n])
    np.savetxt(in_g, g_table, delimiter=",", header=header, comments="", fmt="%.15g")
    reference, declared = (
        _solved(call_cli, in_counts),
        _solved(call_cli, in_g, "--accel-units", "g"),
    )
    u_counts, u_g = reference["uncertainty"], declared["uncertainty"]
    assert isinstance(u_counts, dict)
    assert isinstance(u_g, dict)
    np.testing.assert_allclose(_xyz(u_g["offset"]), _xyz(u_counts["offset"]) / PER_G, rtol=1e-6)
    np.testing.assert_allclose(
        _xyz(u_g["sensitivity"]), _xyz(u_counts["sensitivity"]) / PER_G, rtol=1e-6
    )


def test_a_profiles_counts_limits_are_not_applied_to_readings_in_g(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    path = tmp_path / "poses.csv"
    np.savetxt(path, spread_directions(8), delimiter=",", header="ax,ay,az", comments="")
    result = call_cli("solve", str(path), "--accel-units", "g", "--profile", "kxm52-production")
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [
        "calstation: error: --limits/--profile: a profile's limits are in its product's ADC "
        "counts, the poses in g: no limit applies to them; leave out --limits and --profile"
    ]


@pytest.fixture(scope="module")
def ferraris_stream(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """imucal's session under the station's column names (``t`` is the sample number)."""
    path = tmp_path_factory.mktemp("imucal") / "ferraris.csv"
    with gzip.open(FERRARIS, "rt") as src:
        header = src.readline().strip().split(",")
        table = np.loadtxt(src, delimiter=",")
    order = [header.index(c) for c in ("n_samples", "acc_x", "acc_y", "acc_z")]
    order += [header.index(c) for c in ("gyr_x", "gyr_y", "gyr_z")]
    np.savetxt(path, table[:, order], delimiter=",", header=HEADER, comments="", fmt="%.17g")
    return path


def test_the_public_ferraris_session_answers_in_m_s2_and_holds_imucals_figures_within_u(
    call_cli: CliRunner, ferraris_stream: Path
) -> None:
    # imucal's own FerrarisCalibration of this session (docs/benchmarks.md, "Real data"):
    # accelerometer bias 54.77, -62.84, 40.67 mg and scale 0.99675, 1.00244, 1.02340.
    imucal_bias = np.array([54.77, -62.84, 40.67]) * 1e-3 * G0
    imucal_scale = np.array([0.99675, 1.00244, 1.02340])
    data = _solved(
        call_cli, ferraris_stream, "--stream", "--accel-units", "m/s2", "--rate", "102.4"
    )
    assert data["units"]["offset"] == "m/s2"  # type: ignore[index]
    u = data["uncertainty"]
    assert isinstance(u, dict)
    assert (np.abs(_xyz(data["offset"]) - imucal_bias) <= _xyz(u["offset"])).all()
    assert (np.abs(_xyz(data["sensitivity"]) - imucal_scale) <= _xyz(u["sensitivity"])).all()


def test_a_pose_file_in_g_without_spreads_says_what_noise_it_assumed(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    path = tmp_path / "poses.csv"
    means = 0.01 + spread_directions(8) * 1.02
    np.savetxt(path, means, delimiter=",", header="ax,ay,az", comments="", fmt="%.12g")
    result = call_cli("solve", str(path), "--accel-units", "g")
    assert result.returncode == 0, result.stderr
    assert "offset (g)" in result.stdout
    assert "each pose's noise taken as the sensor's (the putter's, 0.00244 g a sample)" in (
        result.stdout.replace("\n", " ")
    )
    assert "counts" not in result.stdout
