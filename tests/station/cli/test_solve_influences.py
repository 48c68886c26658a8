"""``calstation solve``: every influence in U or named as excluded. The temperature of a
pose file's ``temp_c`` column (the drift across the poses at the sensor's declared
coefficients), checked on simulated units with known truth ([JCGM101]_): seeded, so the
same every run."""

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from station.domain.sensors.sensor import OFFSET_TEMPCO_COUNTS_PER_C, SENSITIVITY_TEMPCO_PER_C
from station.simulator.coverage import true_sensitivity
from station.simulator.sensor import SensorTruth, Thermal
from tests.conftest import REPO_ROOT, CliRunner

UNITS = 30
POSE_INTERVAL_S = 30.0
#: The six poses of [Song2006]_: exactly determined, no residual shows the drift.
SIX = np.vstack([np.eye(3), -np.eye(3)])


def _warming_unit(rng: np.random.Generator, path: Path) -> tuple[SensorTruth, np.ndarray]:
    """A unit whose poses (the six of [Song2006]_) are taken 30 s apart as
    its board warms from power-up (0.6 °C over six), its temperature coefficients
    anywhere within the KXM52's datasheet bounds; written with each pose's spread,
    sample count and temperature. Returns the truth at the poses' mean temperature
    and the temperatures."""
    truth = replace(
        SensorTruth.draw(rng),
        offset_tempco_counts_per_c=rng.uniform(-1, 1, 3) * OFFSET_TEMPCO_COUNTS_PER_C,
        sensitivity_tempco_per_c=rng.uniform(-1, 1, 3) * SENSITIVITY_TEMPCO_PER_C,
    )
    temperatures = Thermal().at(POSE_INTERVAL_S * np.arange(len(SIX), dtype=np.float64))
    means = np.array(
        [truth.at(t).still_counts(u[None, :])[0] for t, u in zip(temperatures, SIX, strict=True)]
    )
    means += rng.normal(0.0, 1.0 / 32, means.shape)  # 1 count of noise over 1024 samples
    rows = [
        f"{a[0]:.6f},{a[1]:.6f},{a[2]:.6f},1,1,1,1024,{t:.4f}"
        for a, t in zip(means, temperatures, strict=True)
    ]
    path.write_text("ax,ay,az,sx,sy,sz,n,temp_c\n" + "\n".join(rows) + "\n")
    return truth.at(float(np.mean(temperatures))), temperatures


def _covered(data: dict[str, dict[str, float]], truth: SensorTruth) -> np.ndarray:
    """Which of the offsets and sensitivities hold the truth within ±U."""
    u = data["uncertainty"]
    offset = [
        abs(data["offset"][a] - truth.offset_counts[i]) <= u["offset"][a]
        for i, a in enumerate("xyz")
    ]
    true_s = true_sensitivity(truth, "six")
    sens = [
        abs(data["sensitivity"][a] - true_s[i]) <= u["sensitivity"][a] for i, a in enumerate("xyz")
    ]
    return np.array(offset + sens)


def test_the_temperature_column_puts_the_drift_across_the_poses_in_u(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    # Six poses fit exactly: no residual shows the drift. Without the temperatures the
    # offsets' truths lie outside ±U most of the time (up to 1.1 counts of drift across
    # the poses against a U of tenths); with them about 95 % within.
    rng = np.random.default_rng(43)
    with_t, without_t = [], []
    for unit in range(UNITS):
        path = tmp_path / f"unit{unit}.csv"
        truth, temperatures = _warming_unit(rng, path)
        data = json.loads(call_cli("solve", str(path), "--json").stdout)
        assert data["excluded_influences"] == []
        assert data["temperature_c"]["mean"] == pytest.approx(np.mean(temperatures), abs=1e-3)
        assert data["temperature_c"]["span"] == pytest.approx(np.ptp(temperatures), abs=1e-3)
        with_t.append(_covered(data, truth))
        bare = tmp_path / f"bare{unit}.csv"
        bare.write_text(
            "\n".join(line.rsplit(",", 1)[0] for line in path.read_text().splitlines()) + "\n"
        )
        data = json.loads(call_cli("solve", str(bare), "--json").stdout)
        assert [e["influence"] for e in data["excluded_influences"]] == ["temperature"]
        assert data["temperature_c"] is None
        without_t.append(_covered(data, truth))
    inside, outside = np.array(with_t), np.array(without_t)
    assert 0.90 <= inside.mean() <= 0.99
    assert outside[:, :3].mean() < 0.6


def test_no_temperature_is_named_as_excluded_on_the_screen(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    _warming_unit(np.random.default_rng(5), tmp_path / "warm.csv")
    result = call_cli("solve", str(tmp_path / "warm.csv"))
    assert result.returncode == 0, result.stderr
    screen = " ".join(result.stdout.split())
    assert "temperature: poses at" in screen
    assert "NOT IN U" not in screen
    bare = tmp_path / "bare.csv"
    bare.write_text(
        "\n".join(
            line.rsplit(",", 1)[0] for line in (tmp_path / "warm.csv").read_text().splitlines()
        )
    )
    screen = " ".join(call_cli("solve", str(bare)).stdout.split())
    assert "NOT IN U: temperature: no temperature recorded at the poses" in screen


def test_the_declared_drift_coefficient_sets_the_temperature_term(
    call_cli: CliRunner, tmp_path: Path
) -> None:
    path = tmp_path / "warm.csv"
    _warming_unit(np.random.default_rng(6), path)
    putter = json.loads(call_cli("solve", str(path), "--json").stdout)
    wide = json.loads(call_cli("solve", str(path), "--json", "--offset-tempco", "10").stdout)
    none = json.loads(
        call_cli(
            "solve", str(path), "--json", "--offset-tempco", "0", "--sensitivity-tempco", "0"
        ).stdout
    )
    for axis in "xyz":
        assert none["uncertainty"]["offset"][axis] < putter["uncertainty"]["offset"][axis]
        assert putter["uncertainty"]["offset"][axis] < wide["uncertainty"]["offset"][axis]


def test_a_temperature_that_is_not_one_is_refused(call_cli: CliRunner, tmp_path: Path) -> None:
    path = tmp_path / "cold.csv"
    path.write_text("ax,ay,az,temp_c\n2048,2048,2867,-300\n")
    result = call_cli("solve", str(path))
    assert result.returncode == 2
    assert result.stderr.strip() == (
        f"calstation: error: {path}:2: column temp_c: -300 is not a temperature "
        "(a finite number of °C above absolute zero)"
    )


def test_the_declared_cross_axis_coupling_sets_the_six_parameter_model_term(
    call_cli: CliRunner,
) -> None:
    paper = str(REPO_ROOT / "examples" / "paper_table2.csv")
    putter = json.loads(call_cli("solve", paper, "--json").stdout)["uncertainty"]
    two = json.loads(call_cli("solve", paper, "--json", "--cross-axis", "2").stdout)["uncertainty"]
    one = json.loads(call_cli("solve", paper, "--json", "--cross-axis", "1").stdout)["uncertainty"]
    assert two == putter  # the KXM52's 2 % by default
    for axis in "xyz":
        assert one["sensitivity"][axis] < putter["sensitivity"][axis]
        assert one["offset"][axis] < putter["offset"][axis]
