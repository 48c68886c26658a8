"""``calstation solve``: the JSON contract and bad input, run as a real process."""

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.calibration.synthetic import pose_means, random_unit, spread_directions
from station.errors import InputError
from station.posefile import read_pose_file
from tests.conftest import REPO_ROOT, CliRunner

PAPER_CSV = REPO_ROOT / "examples" / "paper_table2.csv"


def test_json_contract_on_the_paper_example(run_cli: CliRunner) -> None:
    result = run_cli("solve", str(PAPER_CSV), "--json")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert {
        "model",
        "poses",
        "offset",
        "sensitivity",
        "matrix",
        "residual_rms_mg",
        "condition_number",
    } <= set(data)
    assert data["model"] == "six"
    assert data["poses"] == 6
    assert data["offset"]["x"] == pytest.approx(2081.92752, abs=1e-2)
    assert data["k1"] == pytest.approx(0.995797, abs=1e-6)
    s = data["sensitivity"]
    np.testing.assert_allclose(
        np.array(data["matrix"]), np.diag([1 / s["x"], 1 / s["y"], 1 / s["z"]]), rtol=1e-12
    )


def test_readable_table(run_cli: CliRunner) -> None:
    result = run_cli("solve", str(PAPER_CSV))
    assert result.returncode == 0, result.stderr
    assert "2081.9275" in result.stdout
    assert "k1 = 0.995797" in result.stdout


def test_nine_model_on_a_generated_file(run_cli: CliRunner, tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    unit = random_unit(rng, cross_axis=0.02)
    poses = pose_means(unit, spread_directions(18), 0.05, rng)
    path = tmp_path / "poses.csv"
    path.write_text("temp,ax,ay,az,note\n" + "".join(f"25.0,{x},{y},{z},ok\n" for x, y, z in poses))
    result = run_cli("solve", str(path), "--model", "nine", "--json")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["model"] == "nine"
    assert data["poses"] == 18
    np.testing.assert_allclose([data["offset"][a] for a in "xyz"], unit.offset, atol=0.5)
    assert data["standard_errors"] is not None


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("", "the file is empty"),
        ("x,y,z\n1,2,3\n", ":1: header lacks column(s) ax,ay,az"),
        ("ax,ay,az\n2031,1999,1143\n2048,abc,1925\n", ":3: column ay: 'abc' is not a number"),
        ("ax,ay,az\n2031,1999\n", ":2: column az: an empty cell is not a number"),
        ("ax,ay,az\n", "no pose rows after the header"),
        (
            "ax,ay,az\n2031,1999,1143\n2048,1227,1925\n",
            "2 poses given, this model needs at least 6",
        ),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    run_cli: CliRunner, tmp_path: Path, content: str, message: str
) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(content)
    result = run_cli("solve", str(path))
    assert result.returncode == 2
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert str(path) in lines[0]
    assert message in lines[0]


def test_a_degenerate_pose_is_named_by_its_line(run_cli: CliRunner, tmp_path: Path) -> None:
    rows = PAPER_CSV.read_text().splitlines()
    rows[4] = rows[4].replace("2040,2853,2028", "4095,2853,2028")  # pose 4 on line 5
    path = tmp_path / "rail.csv"
    path.write_text("\n".join(rows) + "\n")
    result = run_cli("solve", str(path))
    assert result.returncode == 2
    assert f"{path}:5: pose 4: x is at the ADC rail" in result.stderr
    assert "Traceback" not in result.stderr


def test_missing_file(run_cli: CliRunner, tmp_path: Path) -> None:
    result = run_cli("solve", str(tmp_path / "none.csv"))
    assert result.returncode == 2
    assert "none.csv: no such file" in result.stderr


@settings(max_examples=200)
@given(text=st.text(alphabet="ax yz,0123456789.-e\n\"'", max_size=200))
def test_pose_reader_never_crashes_on_garbage(
    tmp_path_factory: pytest.TempPathFactory, text: str
) -> None:
    path = tmp_path_factory.mktemp("fuzz") / "f.csv"
    path.write_text(text)
    try:
        result = read_pose_file(path)
    except InputError as exc:
        message = str(exc)
    else:
        assert result.poses.shape == (len(result.lines), 3)
        return
    assert message.startswith(str(path))
    assert "\n" not in message
