"""``calstation solve``: the JSON contract and bad input, through the command's entry point
in the test's process (``call_cli``; ``tests/test_cli_entry.py`` runs it as a process)."""

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.domain.errors import InputError
from station.domain.signals.posefile import read_pose_file
from station.simulator.recording import pose_means, random_directions, spread_directions
from station.simulator.sensor import SensorTruth
from tests.conftest import REPO_ROOT, CliRunner, examples

PAPER_CSV = REPO_ROOT / "examples" / "paper_table2.csv"


def test_json_contract_on_the_paper_example(call_cli: CliRunner) -> None:
    result = call_cli("solve", str(PAPER_CSV), "--json")
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


def test_json_carries_the_expanded_uncertainty_of_each_coefficient(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    paper = json.loads(call_cli("solve", str(PAPER_CSV), "--json").stdout)["uncertainty"]
    assert set(paper) == {"k", "offset", "sensitivity"}  # no gyro in a pose file
    assert paper["k"] == 2
    assert all(paper["offset"][a] > 0 and paper["sensitivity"][a] > 0 for a in "xyz")
    # The file's own spreads and sample counts replace the sensor's assumed noise: a
    # quieter, longer capture gives no larger U, and a noisy short one a larger one.
    lines = PAPER_CSV.read_text().splitlines()
    quiet, noisy = tmp_path / "quiet.csv", tmp_path / "noisy.csv"
    quiet.write_text(
        "\n".join([lines[0] + ",sx,sy,sz,n"] + [f"{r},0.6,0.6,0.6,4096" for r in lines[1:]])
    )
    noisy.write_text(
        "\n".join([lines[0] + ",sx,sy,sz,n"] + [f"{r},30,30,30,16" for r in lines[1:]])
    )
    low = json.loads(call_cli("solve", str(quiet), "--json").stdout)["uncertainty"]
    high = json.loads(call_cli("solve", str(noisy), "--json").stdout)["uncertainty"]
    for key in ("offset", "sensitivity"):
        for a in "xyz":
            assert low[key][a] <= paper[key][a] < high[key][a]


def test_a_pose_whose_spread_is_well_above_the_noise_is_named_and_de_weighted(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    lines = PAPER_CSV.read_text().splitlines()
    spreads = ["1.1,0.9,1.0,1024"] * 6
    quiet = tmp_path / "quiet.csv"
    quiet.write_text(
        "\n".join(
            [lines[0] + ",sx,sy,sz,n"]
            + [f"{r},{s}" for r, s in zip(lines[1:], spreads, strict=True)]
        )
    )
    spreads[3] = "1.0,8.2,1.0,1024"  # a knock on y while the fourth pose was taken
    knocked = tmp_path / "knocked.csv"
    knocked.write_text(
        "\n".join(
            [lines[0] + ",sx,sy,sz,n"]
            + [f"{r},{s}" for r, s in zip(lines[1:], spreads, strict=True)]
        )
    )
    calm = json.loads(call_cli("solve", str(quiet), "--json").stdout)
    data = json.loads(call_cli("solve", str(knocked), "--json").stdout)
    assert calm["disturbed_poses"] == []
    assert [d["pose"] for d in data["disturbed_poses"]] == [4]
    # y's noise: the poses' median spread, 0.9
    assert data["disturbed_poses"][0]["spread_over_noise"] == pytest.approx(8.2 / 0.9)
    # Its excess spread (8.15 counts) enters U undivided by the 1024 samples: taken as
    # white noise it would move the pose's mean by 0.26 counts, next to the
    # 3-count model term of U, and leave U within a few per cent.
    assert data["offset"] == calm["offset"]
    assert data["uncertainty"]["offset"]["y"] > 2 * calm["uncertainty"]["offset"]["y"]
    screen = call_cli("solve", str(knocked))
    assert screen.returncode == 0
    assert f"DISTURBED pose 4 ({knocked}:5)" in " ".join(screen.stdout.split())


def test_readable_table(call_cli: CliRunner) -> None:
    result = call_cli("solve", str(PAPER_CSV))
    assert result.returncode == 0, result.stderr
    assert "2081.9275" in result.stdout
    assert "k1 = 0.995797" in result.stdout


def test_nine_model_on_a_generated_file(call_cli: CliRunner, tmp_path: Path) -> None:
    rng = np.random.default_rng(3)
    unit = SensorTruth.draw_accelerometer(rng, cross_axis=0.02)
    poses = pose_means(unit, spread_directions(18), 0.05, rng)
    path = tmp_path / "poses.csv"
    path.write_text("temp,ax,ay,az,note\n" + "".join(f"25.0,{x},{y},{z},ok\n" for x, y, z in poses))
    result = call_cli("solve", str(path), "--model", "nine", "--json")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["model"] == "nine"
    assert data["poses"] == 18
    np.testing.assert_allclose([data["offset"][a] for a in "xyz"], unit.offset_counts, atol=0.5)
    assert data["standard_errors"] is not None


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("", "the file is empty"),
        ("x,y,z\n1,2,3\n", ":1: header lacks column(s) ax,ay,az"),
        ("ax,ay,az\n2031,1999,1143\n2048,abc,1925\n", ":3: column ay: 'abc' is not a number"),
        ("ax,ay,az,sx,sy\n2031,1999,1143,1,1\n", "lacks sz,n: a pose's spread needs sx,sy,sz"),
        ("ax,ay,az,sx,sy,sz,n\n2031,1999,1143,1,1,1,0.5\n", ":2: column n: 0.5 is not a sample"),
        ("ax,ay,az,sx,sy,sz,n\n2031,1999,1143,-1,1,1,9\n", ":2: column sx: -1 is not a spread"),
        ("ax,ay,az\n2031,1999\n", ":2: column az: an empty cell is not a number"),
        ("ax,ay,az\n", "no pose rows after the header"),
        (
            "ax,ay,az\n2031,1999,1143\n2048,1227,1925\n",
            "2 poses given, this model needs at least 6",
        ),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    call_cli: CliRunner, tmp_path: Path, content: str, message: str
) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(content)
    result = call_cli("solve", str(path))
    assert result.returncode == 2
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert str(path) in lines[0]
    assert message in lines[0]


def test_a_degenerate_pose_is_named_by_its_line(call_cli: CliRunner, tmp_path: Path) -> None:
    rows = PAPER_CSV.read_text().splitlines()
    rows[4] = rows[4].replace("2040,2853,2028", "4095,2853,2028")  # pose 4 on line 5
    path = tmp_path / "rail.csv"
    path.write_text("\n".join(rows) + "\n")
    result = call_cli("solve", str(path))
    assert result.returncode == 2
    assert f"{path}:5: pose 4: x is at the ADC rail" in result.stderr
    assert "Traceback" not in result.stderr


def test_missing_file(call_cli: CliRunner, tmp_path: Path) -> None:
    result = call_cli("solve", str(tmp_path / "none.csv"))
    assert result.returncode == 2
    assert "none.csv: no such file" in result.stderr


@settings(max_examples=examples(200))
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


def _write(path: Path, poses: np.ndarray) -> Path:
    np.savetxt(path, poses, delimiter=",", header="ax,ay,az", comments="", fmt="%.4f")
    return path


def test_an_inconsistent_pose_is_excluded_and_named(call_cli: CliRunner, tmp_path: Path) -> None:
    rng = np.random.default_rng(12)
    unit = SensorTruth.draw_accelerometer(rng, cross_axis=0.02)
    directions = spread_directions(12)
    poses = pose_means(unit, directions, 0.05, rng)
    poses[2] += 100.0 * directions[2]  # pose 3, line 4
    path = _write(tmp_path / "poses.csv", poses)
    result = call_cli("solve", str(path), "--model", "nine", "--json")
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["excluded"] == [3]
    assert data["residual_limit_counts"] == pytest.approx(2.0)
    assert data["sensitivity_convention"].startswith("1/diag(C), C upper-triangular")
    assert data["standard_errors"]["dof"] == 11 - 9
    np.testing.assert_allclose([data["offset"][a] for a in "xyz"], unit.offset_counts, atol=0.5)
    text = call_cli("solve", str(path), "--model", "nine")
    assert f"EXCLUDED pose 3 ({path}:4)" in text.stdout
    assert "no ± shown: 2 degree(s) of freedom" in text.stdout


def test_a_profile_sets_the_residual_limit(call_cli: CliRunner, tmp_path: Path) -> None:
    rng = np.random.default_rng(13)
    unit = SensorTruth.draw_accelerometer(rng)
    directions = spread_directions(12)
    poses = pose_means(unit, directions, 0.05, rng)
    poses[5] += 30.0 * directions[5]
    path = _write(tmp_path / "poses.csv", poses)
    limits = tmp_path / "limits.toml"
    shipped = (REPO_ROOT / "station" / "domain" / "profiles" / "limits.toml").read_text()
    header = "[profiles.kxm52-production]\n"  # the default profile (not the file's last)
    limits.write_text(shipped.replace(header, header + "fit_residual_counts = { upper = 50.0 }\n"))
    loose = json.loads(call_cli("solve", str(path), "--limits", str(limits), "--json").stdout)
    strict = json.loads(call_cli("solve", str(path), "--json").stdout)
    assert (loose["excluded"], loose["residual_limit_counts"]) == ([], 50.0)
    assert strict["excluded"] == [6]


@pytest.mark.parametrize(
    ("rows", "message"),
    [
        ("0.01,-0.02,1.00\n" * 7, "look like acceleration in g or m/s²"),
        (
            "2048,2048,3400\n2048,2048,1229\n2867,2048,2048\n1229,2048,2048\n"
            "2048,2867,2048\n2048,1229,2048\n2521,2521,2521\n",
            "pose 1: z reads beyond the datasheet",
        ),
    ],
)
def test_refusals_name_the_real_cause(
    call_cli: CliRunner, tmp_path: Path, rows: str, message: str
) -> None:
    path = tmp_path / "bad.csv"
    path.write_text("ax,ay,az\n" + rows)
    result = call_cli("solve", str(path))
    assert result.returncode == 2
    assert message in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


@pytest.mark.timeout(300)
def test_100000_poses_solve_or_refuse_in_one_line(call_cli: CliRunner, tmp_path: Path) -> None:
    # Memory linear in the poses: no N×N table (1e5² would be 75 GiB of float64).
    rng = np.random.default_rng(14)
    unit = SensorTruth.draw_accelerometer(rng, cross_axis=0.02)
    poses = pose_means(unit, random_directions(rng, 100_000), 0.05, rng)
    result = call_cli(
        "solve", str(_write(tmp_path / "many.csv", poses)), "--model", "nine", "--json"
    )
    assert result.returncode == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["poses"] == 100_000
    assert data["excluded"] == []
    assert data["near_duplicates"] > 0  # reported, not refused
    in_g = call_cli("solve", str(_write(tmp_path / "g.csv", (poses - 2048) / 819.2)))
    assert in_g.returncode == 2
    assert "Traceback" not in in_g.stderr
    assert len(in_g.stderr.strip().splitlines()) == 1
