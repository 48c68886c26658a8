"""``calstation gyro``: the fit and simulate commands. The log is simulated by a real
process; the commands run through their entry point in the test's process (``call_cli``)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from station.domain.gyro.log import NUMERIC_COLUMNS
from tests.conftest import REPO_ROOT, CliRunner

HEADER = ",".join(NUMERIC_COLUMNS)


@pytest.fixture(scope="module")
def centrifuge_log(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A per-sample log of the default test (segment column), written by the CLI itself."""
    path = tmp_path_factory.mktemp("gyro") / "centrifuge.csv"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "station",
            "gyro",
            "simulate-centrifuge",
            "--out",
            str(path),
            "--seed",
            "4",
            "--samples-per-dwell",
            "4",
            "--noise-dps",
            "0.02",
        ],
        capture_output=True,
        text=True,
        check=False,
        cwd=REPO_ROOT,
    )
    assert result.returncode == 0, result.stderr
    return path


def test_simulate_writes_the_log_with_segments(centrifuge_log: Path) -> None:
    lines = centrifuge_log.read_text(encoding="utf-8").splitlines()
    assert lines[0] == HEADER + ",segment"
    assert len(lines) == 1 + 4 * 294


def test_fit_json_contract(call_cli: CliRunner, centrifuge_log: Path, tmp_path: Path) -> None:
    plot = tmp_path / "fig10.png"
    result = call_cli("gyro", "fit", str(centrifuge_log), "--json", "--plot", str(plot))
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert len(data["bias_dps"]) == 3
    for key in ("scale_matrix", "bias_g_sensitivity_dps_per_g", "g_sensitivity_ppm_per_g"):
        assert [len(row) for row in data[key]] == [3, 3, 3]
        assert [len(row) for row in data["standard_errors"][key]] == [3, 3, 3]
    assert data["sense_axis"] == ["y", "z", "y"]
    n = data["g_sensitivity_ppm_per_g"]
    se = data["standard_errors"]["g_sensitivity_ppm_per_g"]
    for (i, j), truth in zip(((0, 1), (1, 2), (2, 1)), (581.0, 612.0, -613.0), strict=True):
        assert abs(n[i][j] - truth) < 5 * se[i][j]
    assert len(data["residual_rms_dps"]) == 3
    assert data["unestimable"] == []
    assert [c["verdict"] for c in data["comparison"]] == ["scale-factor"] * 3
    assert [a["rank"] for a in data["identifiability"]["axes"]] == [10, 10, 10]
    assert data["dwells"] == 294
    assert plot.read_bytes().startswith(b"\x89PNG")


def test_fit_prints_a_table_without_json(call_cli: CliRunner, centrifuge_log: Path) -> None:
    result = call_cli("gyro", "fit", str(centrifuge_log))
    assert result.returncode == 0, result.stderr
    assert "gyro x: form scale-factor" in result.stdout


def test_single_mount_log_is_refused_for_the_form_question(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    log = tmp_path / "single.csv"
    made = call_cli(
        "gyro", "simulate-centrifuge", "--single-mount", "--seed", "1", "--out", str(log)
    )
    assert made.returncode == 0, made.stderr
    result = call_cli("gyro", "fit", str(log), "--json")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["g_sensitivity_ppm_per_g"][0][1] is None
    assert data["bias_g_sensitivity_dps_per_g"][0][1] is None
    reasons = {t["term"]: t["reason"] for t in data["unestimable"]}
    assert "flip the mount" in reasons["N_xy"]
    assert [c["verdict"] for c in data["comparison"]] == [None, None, None]
    refused = call_cli("gyro", "fit", str(log), "--plot", str(tmp_path / "p.png"))
    assert refused.returncode == 2
    assert "N_xy" in refused.stderr
    assert "Traceback" not in refused.stderr


def test_simulate_to_stdout_uses_the_truth_options(call_cli: CliRunner, tmp_path: Path) -> None:
    result = call_cli(
        "gyro",
        "simulate-centrifuge",
        "--seed",
        "2",
        "--ppm",
        "0,0,0",
        "--bias-form",
        "0.02,0.02,0.02",
        "--sense-axes",
        "z,x,x",
        "--noise-dps",
        "0.005",
    )
    assert result.returncode == 0, result.stderr
    log = tmp_path / "bias.csv"
    log.write_text(result.stdout, encoding="utf-8")
    fitted = json.loads(call_cli("gyro", "fit", str(log), "--json").stdout)
    assert [c["verdict"] for c in fitted["comparison"]] == ["bias"] * 3
    b = fitted["bias_g_sensitivity_dps_per_g"]
    assert [round(b[0][2], 3), round(b[1][0], 3), round(b[2][0], 3)] == [0.02, 0.02, 0.02]


def _one_line_error(result: subprocess.CompletedProcess[str], *parts: str) -> None:
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1
    assert result.stderr.startswith("calstation: error: ")
    for part in parts:
        assert part in result.stderr


def test_missing_file(call_cli: CliRunner, tmp_path: Path) -> None:
    _one_line_error(call_cli("gyro", "fit", str(tmp_path / "none.csv")), "none.csv: no such file")


def test_missing_column(call_cli: CliRunner, tmp_path: Path) -> None:
    log = tmp_path / "cols.csv"
    log.write_text(HEADER.replace(",gyro_y", "") + "\n", encoding="utf-8")
    _one_line_error(call_cli("gyro", "fit", str(log)), "cols.csv: missing column gyro_y")


def test_non_numeric_cell_names_file_line_and_column(call_cli: CliRunner, tmp_path: Path) -> None:
    log = tmp_path / "cell.csv"
    rows = [",".join(["1"] * 10)] * 3
    rows[2] = ",".join(["1"] * 5 + ["x1"] + ["1"] * 4)
    log.write_text(HEADER + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    _one_line_error(
        call_cli("gyro", "fit", str(log)), "cell.csv:4: column acc_y: 'x1' is not a number"
    )


def test_too_few_rows(call_cli: CliRunner, tmp_path: Path) -> None:
    log = tmp_path / "short.csv"
    log.write_text(HEADER + "\n" + "\n".join([",".join(["1"] * 10)] * 5) + "\n", encoding="utf-8")
    _one_line_error(
        call_cli("gyro", "fit", str(log)), "short.csv: 5 dwells in the log", "at least 11"
    )
    log.write_text(HEADER + "\n", encoding="utf-8")
    _one_line_error(call_cli("gyro", "check", str(log)), "short.csv: the log holds no dwells")


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("--ppm", "1,2"), "--ppm: expected three numbers"),
        (("--sense-axes", "x,q,y"), "--sense-axes: expected three of x, y, z"),
        (("--g-step", "0"), "--g-step: must be positive"),
        (("--samples-per-dwell", "0"), "--samples-per-dwell: must be at least 1"),
    ],
)
def test_simulate_refuses_bad_options(
    call_cli: CliRunner, args: tuple[str, ...], message: str
) -> None:
    _one_line_error(call_cli("gyro", "simulate-centrifuge", *args), message)


def test_fit_refuses_a_bad_plot_suffix(
    call_cli: CliRunner, centrifuge_log: Path, tmp_path: Path
) -> None:
    _one_line_error(
        call_cli("gyro", "fit", str(centrifuge_log), "--plot", str(tmp_path / "f.jpg")),
        "must end in .png or .svg",
    )


def test_check_accepts_the_full_plan(call_cli: CliRunner, centrifuge_log: Path) -> None:
    result = call_cli("gyro", "check", str(centrifuge_log), "--json")
    assert result.returncode == 0, result.stderr
    axes = json.loads(result.stdout)["axes"]
    assert [a["form_question"] for a in axes] == [True, True, True]


def test_check_refuses_a_single_mount_log(call_cli: CliRunner, tmp_path: Path) -> None:
    log = tmp_path / "single.csv"
    assert (
        call_cli("gyro", "simulate-centrifuge", "--single-mount", "--out", str(log)).returncode == 0
    )
    result = call_cli("gyro", "check", str(log))
    assert "not estimable: N_xy: confounded with scale-factor non-linearity ω³" in result.stdout
    _one_line_error(result, "cannot tell bias-form from scale-factor-form", "gyro x", "N_xy")


def test_fit_refuses_a_bad_alpha(call_cli: CliRunner, centrifuge_log: Path) -> None:
    _one_line_error(
        call_cli("gyro", "fit", str(centrifuge_log), "--alpha", "1.5"), "--alpha: must lie between"
    )
