"""``calstation demo``: the README's main command, end to end on virtual putters."""

import json
import os
import re
import sqlite3
from pathlib import Path

import numpy as np
import pytest

from station.domain.product.products import load_products
from tests.conftest import CliRunner
from tests.db.records import make_record


def test_demo_json_estimates_land_on_the_truth(run_cli: CliRunner, tmp_path: Path) -> None:
    env_dir = tmp_path / "data"
    env = {**os.environ, "CALSTATION_DATA_DIR": str(env_dir)}
    env.pop("CALSTATION_DATABASE_URL", None)
    result = run_cli("demo", "--units", "2", "--json", "--speed", "20", env=env, timeout=180)
    assert result.returncode == 0, result.stderr
    units = json.loads(result.stdout)  # stdout holds only the JSON
    assert [u["serial"] for u in units] == ["PT001001", "PT001002"]
    for unit in units:
        assert unit["verdict"] == "pass", unit["failures"]
        truth, estimate = unit["truth"], unit["estimate"]
        for axis in "xyz":
            assert abs(estimate["offset"][axis] - truth["offset"][axis]) < 1.0
            ratio = estimate["sensitivity"][axis] / truth["sensitivity"][axis]
            assert abs(ratio - 1) < 1e-3
    assert "PASS" in result.stderr  # the screens went to stderr
    # A newcomer's first screen says what the demo does, and no port trouble.
    assert "demo: 2 virtual putters, each plugged into" in result.stderr
    assert "no such port" not in result.stderr
    with sqlite3.connect(env_dir / "calstation.sqlite3") as db:
        stored = db.execute("select run_id, verdict, lot from runs order by started_at").fetchall()
    assert [(u["run_id"].replace("-", ""), u["verdict"], "demo-lot") for u in units] == [
        (run_id.replace("-", ""), verdict, lot) for run_id, verdict, lot in stored
    ]
    assert np.isfinite([u["estimate"]["offset"]["x"] for u in units]).all()

    # Run again on the same data, the demo takes the next new units, as a line does: the
    # README's demos calibrate units whatever they ran before, in any order.
    for expected in ("PT001003", "PT001004"):
        again = run_cli("demo", "--units", "1", "--json", "--speed", "20", env=env, timeout=180)
        assert again.returncode == 0, again.stderr
        assert [(u["serial"], u["verdict"]) for u in json.loads(again.stdout)] == [
            (expected, "pass")
        ]
        assert "calibrate again?" not in again.stderr


def test_a_demo_that_calibrates_nothing_says_why_and_exits_2(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    golden = {
        "serial": "GU-001",
        "offset_counts": [2048.0, 2048.0, 2048.0],
        "sensitivity_counts_per_g": [819.2, 819.2, 819.2],
    }
    env = {
        **os.environ,
        "CALSTATION_DATA_DIR": str(tmp_path),
        "CALSTATION_GOLDEN": json.dumps(golden),
    }
    env.pop("CALSTATION_DATABASE_URL", None)
    result = run_cli("demo", "--units", "1", "--speed", "20", env=env, timeout=120)
    assert result.returncode == 2, result.stderr
    assert result.stderr.splitlines()[-1] == (
        "calstation: error: demo: no unit was calibrated: GOLDEN UNIT due: scan golden unit "
        "GU-001 before the next unit (every 8 h and at each shift start)"
    )


def test_unreadable_outbox_files_no_longer_stop_the_demo(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    env_dir = tmp_path / "data"
    outbox = env_dir / "outbox"
    outbox.mkdir(parents=True)
    (outbox / "torn.json").write_text('{"run_id": "0c8f", "serial": "PT0')
    (outbox / "empty.json").write_bytes(b"")
    (outbox / "binary.json").write_bytes(bytes(range(256)))
    waiting = make_record(serial="PT000777")
    (outbox / f"{waiting.run_id}.json").write_text(waiting.model_dump_json())
    env = {**os.environ, "CALSTATION_DATA_DIR": str(env_dir)}
    env.pop("CALSTATION_DATABASE_URL", None)
    result = run_cli("demo", "--units", "1", "--json", "--speed", "20", env=env, timeout=180)
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    assert "3 unreadable set aside: see calstation outbox list" in result.stderr
    assert sorted(p.name for p in (outbox / "unreadable").glob("*.json")) == [
        "binary.json",
        "empty.json",
        "torn.json",
    ]
    assert not list(outbox.glob("*.json"))  # the waiting run and the demo's run are stored
    with sqlite3.connect(env_dir / "calstation.sqlite3") as db:
        serials = {serial for (serial,) in db.execute("select serial from runs")}
    assert serials == {"PT000777", json.loads(result.stdout)[0]["serial"]}


@pytest.mark.timeout(240)
def test_the_demo_calibrates_the_whole_unit_with_its_profile(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    env = {**os.environ, "CALSTATION_DATA_DIR": str(tmp_path / "data")}
    env.pop("CALSTATION_DATABASE_URL", None)
    args = ("demo", "--profile", "whole-unit", "--units", "1", "--json", "--speed", "20")
    result = run_cli(*args, env=env, timeout=220)
    assert result.returncode == 0, result.stderr
    (unit,) = json.loads(result.stdout)
    assert unit["verdict"] == "pass", unit["failures"]
    k = np.array(unit["estimate"]["gyro_matrix"])
    # K in the calibrated accelerometer's frame: the gyros' own errors plus that frame's
    # tilt (under 2 %) off the body axes, within the profile's bounds.
    assert np.abs(np.diag(k) - 1).max() < 0.02
    assert not np.allclose(k, np.eye(3), atol=1e-3)
    assert "verification move: turn the putter face up" in result.stderr
    # Before it wrote them, the station read the gyro coefficients the unit held too:
    # a virtual putter's, never written, are zero bias and the identity.
    with sqlite3.connect(tmp_path / "data" / "calstation.sqlite3") as db:
        [(stored,)] = db.execute("select as_found from runs").fetchall()
    gyro = json.loads(stored)["gyro"]
    assert gyro["written"] is False
    assert gyro["offset"] == [0.0, 0.0, 0.0]
    assert gyro["matrix"] == [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def test_a_demo_of_a_product_records_its_part_number(run_cli: CliRunner, tmp_path: Path) -> None:
    env = {**os.environ, "CALSTATION_DATA_DIR": str(tmp_path)}
    env.pop("CALSTATION_DATABASE_URL", None)
    args = ("demo", "--units", "1", "--json", "--speed", "20", "--part-number", "DIXX-A12")
    result = run_cli(*args, env=env, timeout=180)
    assert result.returncode == 0, result.stderr
    [unit] = json.loads(result.stdout)
    with sqlite3.connect(tmp_path / "calstation.sqlite3") as db:
        stored = db.execute("select serial, part_number from runs").fetchall()
    assert stored == [(unit["serial"], "DIXX-A12")]


def test_a_demo_with_a_configuration_runs_as_the_station_it_names(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    env = {**os.environ, "CALSTATION_DATA_DIR": str(tmp_path)}
    for name in ("CALSTATION_DATABASE_URL", "CALSTATION_STATION_ID", "CALSTATION_OPERATOR_ID"):
        env.pop(name, None)
    config = tmp_path / "station.toml"
    config.write_text('station_id = "line2-st9"\noperator_id = "qa-ann"\n')
    args = ("demo", "--units", "1", "--json", "--speed", "20", "--config", str(config))
    result = run_cli(*args, env=env, timeout=180)
    assert result.returncode == 0, result.stderr
    [unit] = json.loads(result.stdout)
    with sqlite3.connect(tmp_path / "calstation.sqlite3") as db:
        stored = db.execute("select serial, station_id, operator_id, lot from runs").fetchall()
    # The file's ids; the demo's own lot, which the file leaves unnamed.
    assert stored == [(unit["serial"], "line2-st9", "qa-ann", "demo-lot")]


@pytest.mark.parametrize(
    ("part_number", "line"),
    [
        ("DIXX-Z9", "unknown part number 'DIXX-Z9'; known: DIXX-A12, DIXX-D16"),
        ("dixx a12", "unknown part number 'dixx a12'"),
    ],
)
def test_a_demo_of_a_product_it_cannot_run_is_one_line_and_exit_2(
    run_cli: CliRunner, tmp_path: Path, part_number: str, line: str
) -> None:
    env = {**os.environ, "CALSTATION_DATA_DIR": str(tmp_path)}
    env.pop("CALSTATION_DATABASE_URL", None)
    result = run_cli("demo", "--units", "1", "--part-number", part_number, env=env, timeout=60)
    assert result.returncode == 2
    [said] = result.stderr.strip().splitlines()
    assert said.startswith(f"calstation: error: {line}"), said


def test_a_demo_in_korean_says_the_runs_lines_in_korean(run_cli: CliRunner, tmp_path: Path) -> None:
    env = {**os.environ, "CALSTATION_DATA_DIR": str(tmp_path), "CALSTATION_LANGUAGE": "zh"}
    env.pop("CALSTATION_DATABASE_URL", None)
    args = ("demo", "--units", "1", "--speed", "40", "--language", "ko")  # the flag wins
    result = run_cli(*args, env=env, timeout=180)
    assert result.returncode == 0, result.stderr
    said = result.stdout + result.stderr
    assert re.search(r"PT\d{6}: 교정 시작 \(실행 [0-9a-f-]{36}\)", said)
    assert "데모: 가상 퍼터 1개, 스크립트 작업자가 각각 차례로 " in said
    # Every pose, by its Korean name, and the verdict and where the unit goes.
    for pose in ("페이스 위", "페이스 아래", "토우 위", "토우 아래", "샤프트 위", "샤프트 아래"):
        assert re.search(rf"PT\d{{6}}: 자세 \d\({pose}\) 측정 완료", said), pose
    assert re.search(r"PT\d{6}: 합격: 출하$", said, re.MULTILINE)
    assert "유닛 1개 교정 완료; 전송 대기 0; 데이터베이스 " in said
    assert "결과 데이터베이스: 연결됨" in said
    for english in (
        "calibration started",
        "captured",
        "PASS",
        "ship",
        "virtual putter",
        "database:",
    ):
        assert english not in said, english
    refused = run_cli("demo", "--units", "1", "--language", "fr", env=env, timeout=60)
    assert refused.returncode == 2
    [said] = refused.stderr.strip().splitlines()
    assert said.startswith("calstation: error: station configuration: language: ")


def test_a_demo_of_dixx_d16_calibrates_its_16_bit_units_and_passes_them(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    env = {**os.environ, "CALSTATION_DATA_DIR": str(tmp_path)}
    env.pop("CALSTATION_DATABASE_URL", None)
    args = ("demo", "--units", "2", "--json", "--speed", "20", "--part-number", "DIXX-D16")
    result = run_cli(*args, env=env, timeout=180)
    assert result.returncode == 0, result.stderr
    units = json.loads(result.stdout)
    assert len(units) == 2
    assert len(re.findall(r"PT\d{6}: PASS: ship$", result.stderr, re.MULTILINE)) == 2
    per_g = load_products().get("DIXX-D16").sensor.counts_per_g
    for unit in units:
        assert unit["verdict"] == "pass", unit["failures"]
        truth, estimate = unit["truth"], unit["estimate"]
        for axis in "xyz":
            # The 12-bit demo's bounds in g (1 count of 819.2 counts/g, 0.1 %).
            assert abs(estimate["offset"][axis] - truth["offset"][axis]) < per_g / 819.2
            ratio = estimate["sensitivity"][axis] / truth["sensitivity"][axis]
            assert abs(ratio - 1) < 1e-3
    with sqlite3.connect(tmp_path / "calstation.sqlite3") as db:
        stored = db.execute("select part_number, limits_name from runs").fetchall()
        means = db.execute("select mean_x, mean_y, mean_z from poses").fetchall()
    assert stored == [("DIXX-D16", "dixx-d16-production")] * 2
    assert max(map(max, means)) > 4095  # the record holds the 16-bit sensor's counts
