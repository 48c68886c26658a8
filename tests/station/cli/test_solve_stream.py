"""``calstation solve LOG.csv --stream``: JSON contract, truth recovered, bad input."""

import json
import re
from pathlib import Path

import numpy as np
import pytest

from station.domain.errors import InputError
from station.domain.gyro.motion import StreamError
from station.domain.gyro.motion.stream_file import read_stream_file
from station.simulator.recording import (
    StreamPlan,
    k_in_calibrated_frame,
    pose_orientations,
    random_imu,
    recorded_stream,
    spread_directions,
)
from station.simulator.sensor import SensorTruth
from tests.conftest import CliRunner

HEADER = "t,ax,ay,az,gx,gy,gz"
PLAN = StreamPlan(rate_hz=200.0, still_s=1.5, move_s=1.0)


def _write(path: Path, rows: np.ndarray, header: str = HEADER) -> Path:
    np.savetxt(path, rows, delimiter=",", header=header, comments="", fmt="%.9g")
    return path


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> tuple[SensorTruth, np.ndarray]:
    rng = np.random.default_rng(11)
    imu = random_imu(rng)
    stream = recorded_stream(rng, imu, pose_orientations(rng, spread_directions(12)), PLAN)
    return imu, np.column_stack([stream.t, stream.accel_counts, stream.gyro_dps])


def test_json_keeps_the_solve_keys_and_adds_poses_and_gyro(
    call_cli: CliRunner, tmp_path: Path, recorded: tuple[SensorTruth, np.ndarray]
) -> None:
    imu, rows = recorded
    path = _write(tmp_path / "log.csv", rows)
    result = call_cli("solve", str(path), "--stream", "--model", "nine", "--json")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert {"model", "method", "offset", "sensitivity", "matrix", "residual_rms_mg"} <= set(data)
    assert data["poses"] == 12
    gyro = data["gyro"]
    k = np.array(gyro["scale_matrix"])
    se = np.array(gyro["scale_matrix_standard_errors"])
    assert (np.abs(k - k_in_calibrated_frame(imu, "nine")) <= 5 * se + 1e-4).all()
    assert np.allclose(gyro["bias_dps"], imu.gyro_bias_dps, atol=0.01)
    assert len(gyro["residual_deg"]) == 11
    assert gyro["unusable_moves"] == []
    assert data["disturbed_poses"] == []  # every still as quiet as the others
    # One shape for the uncertainties, every coefficient measured: the gyro's too.
    u = data["uncertainty"]
    assert set(u) == {"k", "offset", "sensitivity", "gyro_bias_dps", "gyro_matrix", "matrix"}
    assert u["k"] == 2
    # The nine-parameter matrix C is upper-triangular: U above its diagonal, none below.
    u_c = np.array(u["matrix"])
    assert (u_c[np.triu_indices(3)] > 0).all()
    assert (u_c[np.tril_indices(3, -1)] == 0).all()
    # K's U: twice the fit's σ and the moves' geometry, in quadrature (docs/calibration.md)
    assert (np.array(u["gyro_matrix"]) >= 2 * se * (1 - 1e-9)).all()
    assert (np.array(u["gyro_matrix"]) > 2 * se * 1.001).any()
    assert len(u["gyro_bias_dps"]) == 3
    # The truth within ±U (the recording's units are the simulator's own, exact here).
    error = np.abs(np.array(gyro["bias_dps"]) - imu.gyro_bias_dps)
    assert (error <= np.array(u["gyro_bias_dps"]) * 2.5).all()
    offset_error = np.abs([data["offset"][a] - imu.offset_counts[i] for i, a in enumerate("xyz")])
    assert (offset_error <= 2.5 * np.array([u["offset"][a] for a in "xyz"])).all()


def test_a_temperature_column_puts_the_drift_in_u_and_its_absence_is_named(
    call_cli: CliRunner, tmp_path: Path, recorded: tuple[SensorTruth, np.ndarray]
) -> None:
    _, rows = recorded
    bare = _write(tmp_path / "log.csv", rows)
    warming = np.linspace(25.0, 26.0, len(rows))  # a board warming by 1 °C over the run
    warm = _write(tmp_path / "warm.csv", np.column_stack([rows, warming]), HEADER + ",temp_c")
    without = json.loads(
        call_cli("solve", str(bare), "--stream", "--model", "nine", "--json").stdout
    )
    with_t = json.loads(
        call_cli("solve", str(warm), "--stream", "--model", "nine", "--json").stdout
    )
    assert [e["influence"] for e in without["excluded_influences"]] == [
        "temperature",
        "gyro_bias_repeatability",
    ]
    assert without["temperature_c"] is None
    assert [e["influence"] for e in with_t["excluded_influences"]] == ["gyro_bias_repeatability"]
    assert 25.0 < with_t["temperature_c"]["mean"] < 26.0
    assert 0.8 < with_t["temperature_c"]["span"] < 1.0  # the stills' means, first to last
    assert all(
        with_t["uncertainty"]["offset"][a] > without["uncertainty"]["offset"][a] for a in "xyz"
    )
    screen = " ".join(call_cli("solve", str(bare), "--stream").stdout.split())
    assert "NOT IN U: temperature: no temperature recorded at the poses" in screen


def test_a_declared_gyro_bias_repeatability_is_in_the_gyro_bias_u(
    call_cli: CliRunner, tmp_path: Path, recorded: tuple[SensorTruth, np.ndarray]
) -> None:
    _, rows = recorded
    path = _write(tmp_path / "log.csv", rows)
    session = json.loads(call_cli("solve", str(path), "--stream", "--json").stdout)
    declared = json.loads(
        call_cli(
            "solve", str(path), "--stream", "--json", "--gyro-bias-repeatability", "0.05"
        ).stdout
    )
    assert "gyro_bias_repeatability" in [e["influence"] for e in session["excluded_influences"]]
    assert "gyro_bias_repeatability" not in [
        e["influence"] for e in declared["excluded_influences"]
    ]
    own = np.array(session["uncertainty"]["gyro_bias_dps"]) / 2
    # k·√(u_session² + 0.05²): the repeatability in quadrature with the session's own
    np.testing.assert_allclose(
        declared["uncertainty"]["gyro_bias_dps"], 2 * np.sqrt(own**2 + 0.05**2), rtol=1e-9
    )


def test_lost_samples_make_a_move_unusable_and_say_so(
    call_cli: CliRunner, tmp_path: Path, recorded: tuple[SensorTruth, np.ndarray]
) -> None:
    _, rows = recorded
    still_n, move_n = round(PLAN.still_s * PLAN.rate_hz), round(PLAN.move_s * PLAN.rate_hz)
    middle_of_third_move = 3 * still_n + 2 * move_n + move_n // 2
    path = _write(
        tmp_path / "gap.csv",
        np.delete(rows, range(middle_of_third_move, middle_of_third_move + 5), axis=0),
    )
    result = call_cli("solve", str(path), "--stream", "--model", "nine", "--json")
    assert result.returncode == 0, result.stderr
    gyro = json.loads(result.stdout)["gyro"]
    assert [u["move"] for u in gyro["unusable_moves"]] == [2]
    assert "gap" in gyro["unusable_moves"][0]["reason"]
    assert 2 not in gyro["moves_used"]


def test_text_output_names_k_and_the_residuals(
    call_cli: CliRunner, tmp_path: Path, recorded: tuple[SensorTruth, np.ndarray]
) -> None:
    _, rows = recorded
    path = _write(tmp_path / "log.csv", rows)
    result = call_cli("solve", str(path), "--stream", "--model", "nine")
    assert result.returncode == 0, result.stderr
    assert "12 still poses (still window 0.75 s) at 200 samples/s" in result.stdout
    assert "gyro K z:" in result.stdout


def test_the_screen_shows_k_with_the_jsons_expanded_uncertainty(
    call_cli: CliRunner, tmp_path: Path, recorded: tuple[SensorTruth, np.ndarray]
) -> None:
    # One U for K: the screen's ± is the JSON's U (fit, geometry, coupling; k = 2),
    # not the fit's 1-σ standard errors.
    _, rows = recorded
    path = _write(tmp_path / "log.csv", rows)
    for model in ("six", "nine"):
        screen = call_cli("solve", str(path), "--stream", "--model", model)
        data = json.loads(
            call_cli("solve", str(path), "--stream", "--model", model, "--json").stdout
        )
        shown = np.array(
            [
                [float(v) for v in re.findall(r"±([0-9.]+)", line)]
                for line in screen.stdout.splitlines()
                if line.strip().startswith("gyro K ")
            ]
        )
        u = np.array(data["uncertainty"]["gyro_matrix"])
        se = np.array(data["gyro"]["scale_matrix_standard_errors"])
        assert shown.shape == (3, 3)
        assert np.allclose(shown, u, atol=0.6e-5)
        assert not np.allclose(shown, se, atol=0.6e-5)
        assert "U (k=2)" in screen.stdout


def _refused(call_cli: CliRunner, path: Path, *extra: str) -> str:
    result = call_cli("solve", str(path), "--stream", *extra)
    assert result.returncode == 2, result.stdout
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert str(path) in lines[0]
    return lines[0]


def test_missing_column_is_refused(call_cli: CliRunner, tmp_path: Path) -> None:
    path = _write(tmp_path / "nogz.csv", np.zeros((3, 6)), "t,ax,ay,az,gx,gy")
    assert "header lacks column(s) gz" in _refused(call_cli, path)


def test_time_going_back_is_named(tmp_path: Path, recorded: tuple[SensorTruth, np.ndarray]) -> None:
    _, rows = recorded
    back = rows.copy()
    back[100, 0] = back[98, 0]
    path = _write(tmp_path / "back.csv", back)
    with pytest.raises(StreamError, match="t does not increase at data row 101"):
        read_stream_file(path)


def test_a_cell_that_is_not_a_number_is_named_with_its_line(tmp_path: Path) -> None:
    path = tmp_path / "text.csv"
    path.write_text(f"{HEADER}\n0,2048,2048,2867,0,0,0\n0.01,2048,abc,2867,0,0,0\n")
    with pytest.raises(InputError, match=re.escape(f"{path}:3: column ay: 'abc' is not a number")):
        read_stream_file(path)


def test_a_short_row_is_named_with_its_line(tmp_path: Path) -> None:
    path = tmp_path / "short.csv"
    path.write_text(f"{HEADER}\n0,2048,2048,2867,0,0,0\n0.01,2048,2048\n")
    with pytest.raises(InputError, match=re.escape(f"{path}:3: 3 cells, the header has 7")):
        read_stream_file(path)


def test_too_few_stills_are_refused(
    call_cli: CliRunner, tmp_path: Path, recorded: tuple[SensorTruth, np.ndarray]
) -> None:
    _, rows = recorded
    still_n, move_n = round(PLAN.still_s * PLAN.rate_hz), round(PLAN.move_s * PLAN.rate_hz)
    path = _write(tmp_path / "short.csv", rows[: 8 * still_n + 7 * move_n])
    line = _refused(call_cli, path, "--model", "nine")
    assert "8 still poses found, the nine-parameter model needs 9" in line


def _solved(call_cli: CliRunner, path: Path, *options: str) -> dict[str, object]:
    result = call_cli("solve", str(path), "--stream", "--model", "nine", "--json", *options)
    assert result.returncode == 0, result.stderr
    data: dict[str, object] = json.loads(result.stdout)
    return data


def _refused(call_cli: CliRunner, path: Path, *options: str) -> str:
    result = call_cli("solve", str(path), "--stream", "--model", "nine", *options)
    assert result.returncode == 2
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    return lines[0]


def test_declared_units_give_the_same_calibration_and_undeclared_ones_are_named(
    call_cli: CliRunner, tmp_path: Path, recorded: tuple[SensorTruth, np.ndarray]
) -> None:
    _, rows = recorded
    reference = _solved(call_cli, _write(tmp_path / "counts.csv", rows))
    in_g = rows.copy()
    in_g[:, 1:4] = (rows[:, 1:4] - 2048.0) / 819.2
    in_ms2 = in_g.copy()
    in_ms2[:, 1:4] *= 9.80665
    in_rads = rows.copy()
    in_rads[:, 4:7] = np.radians(rows[:, 4:7])
    in_ms = rows.copy()
    in_ms[:, 0] *= 1000.0
    cases = [
        (
            "g.csv",
            in_g,
            ("--accel-units", "g"),
            "at rest: g? use --accel-units g",
        ),
        (
            "ms2.csv",
            in_ms2,
            ("--accel-units", "m/s2"),
            "at rest: m/s²? use --accel-units m/s2",
        ),
        ("rads.csv", in_rads, ("--gyro-units", "rads"), "rad/s? use --gyro-units rads"),
        ("ms.csv", in_ms, ("--time-units", "ms"), "milliseconds? use --time-units ms"),
        ("rate.csv", in_ms, ("--rate", "200"), "milliseconds? use --time-units ms"),
    ]
    # The accelerometer's results come in the unit declared (offset in it, sensitivity as
    # a scale factor for g and m/s²): the counts' answer restated.
    per_unit = {"g": (819.2, 1.0), "m/s2": (819.2 / 9.80665, 1.0)}
    for name, table, declared, refusal in cases:
        path = _write(tmp_path / name, table)
        assert refusal in _refused(call_cli, path), name
        data = _solved(call_cli, path, *declared)
        counts_per_unit, _ = per_unit.get(declared[1], (1.0, 1.0))
        restated = declared[1] in per_unit
        for key in ("offset", "sensitivity"):
            got, want = data[key], reference[key]
            assert isinstance(got, dict)
            assert isinstance(want, dict)
            for axis in "xyz":
                expected = want[axis]
                if restated and key == "offset":
                    expected = (want[axis] - 2048.0) / counts_per_unit
                elif restated:
                    expected = want[axis] / 819.2
                assert got[axis] == pytest.approx(expected, rel=1e-9, abs=1e-8), (name, key, axis)
        gyro, want_gyro = data["gyro"], reference["gyro"]
        assert isinstance(gyro, dict)
        assert isinstance(want_gyro, dict)
        np.testing.assert_allclose(gyro["scale_matrix"], want_gyro["scale_matrix"], atol=1e-6)


def test_units_are_for_streams_and_a_rate_must_be_one(call_cli: CliRunner, tmp_path: Path) -> None:
    poses = tmp_path / "poses.csv"
    poses.write_text("ax,ay,az\n2031,1999,1143\n")
    for option, value in (("--gyro-units", "rads"), ("--known-turn-deg", "360")):
        result = call_cli("solve", str(poses), option, value)
        assert result.returncode == 2
        assert result.stderr.strip().splitlines() == [
            "calstation: error: --gyro-units, --time-units, --rate, --known-turn-deg and "
            "--gyro-bias-repeatability describe a raw stream: use them with --stream"
        ]
    rate = _refused(call_cli, poses, "--rate", "0")
    assert "--rate" in rate
    assert "not a positive rate" in rate


def test_a_gyro_bias_and_noise_above_the_live_limits_are_the_recordings_own(
    call_cli: CliRunner, tmp_path: Path, recorded: tuple[SensorTruth, np.ndarray]
) -> None:
    # A MEMS gyro with a 2 deg/s bias on y (common; the live judge refuses 1 deg/s) and
    # an accelerometer five times noisier than the putter's: the stills are found on the
    # recording's own bias and noise, and the same unit comes out.
    imu, rows = recorded
    reference = _solved(call_cli, _write(tmp_path / "log.csv", rows))
    other = rows.copy()
    other[:, 5] += 2.0
    other[:, 1:4] += np.random.default_rng(3).normal(0.0, 5.0, other[:, 1:4].shape)
    data = _solved(call_cli, _write(tmp_path / "other.csv", other))
    assert data["poses"] == reference["poses"] == 12
    gyro = data["gyro"]
    assert isinstance(gyro, dict)
    assert np.allclose(gyro["bias_dps"], imu.gyro_bias_dps + np.array([0.0, 2.0, 0.0]), atol=0.02)
    reference_gyro = reference["gyro"]
    assert isinstance(reference_gyro, dict)
    np.testing.assert_allclose(gyro["scale_matrix"], reference_gyro["scale_matrix"], atol=2e-3)


def test_no_still_pose_found_says_why_in_the_operators_terms(
    call_cli: CliRunner, tmp_path: Path, recorded: tuple[SensorTruth, np.ndarray]
) -> None:
    # A gyro y whose rate swings ±5 deg/s every 4 s (a unit never at rest, or a broken
    # gyro): hardly a window is still; the refusal says what the judge saw most often.
    _, rows = recorded
    swinging = rows.copy()
    swinging[:, 5] += 5.0 * np.sin(2 * np.pi * rows[:, 0] / 4.0)
    line = _refused(call_cli, _write(tmp_path / "swinging.csv", swinging))
    found = re.search(r"(\d+) still poses found, the nine-parameter model needs 9", line)
    assert found is not None, line
    assert int(found.group(1)) < 9
    assert "windows not still: most often gyro y turning" in line
