"""``calstation solve LOG.csv --stream``: every declared quantity checked against the data.

A recording whose numbers contradict what is declared (or assumed) is refused by the
real process with one line naming the likely cause, exit status 2
(docs/calibration.md, "Declarations checked against the data").
"""

import gzip
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from station.simulator.recording import (
    StreamPlan,
    pose_orientations,
    random_imu,
    recorded_stream,
    spread_directions,
)
from tests.conftest import REPO_ROOT, CliRunner

HEADER = "t,ax,ay,az,gx,gy,gz"
PLAN = StreamPlan(rate_hz=200.0, still_s=1.5, move_s=1.0)
ZERO, PER_G, G0 = 2048.0, 819.2, 9.80665
NUMBER = r"[-+0-9.e]+"
FERRARIS = REPO_ROOT / "tests" / "data" / "imucal" / "example_ferraris_session.csv.gz"


@pytest.fixture(scope="module")
def rows() -> np.ndarray:
    """A simulated putter's recording in its own units: t s, counts, deg/s (12 poses)."""
    rng = np.random.default_rng(17)
    stream = recorded_stream(
        rng, random_imu(rng), pose_orientations(rng, spread_directions(12)), PLAN
    )
    return np.column_stack([stream.t, stream.accel_counts, stream.gyro_dps])


def _in_g(rows: np.ndarray) -> np.ndarray:
    out = rows.copy()
    out[:, 1:4] = (rows[:, 1:4] - ZERO) / PER_G
    return out


def _in_ms2(rows: np.ndarray) -> np.ndarray:
    out = _in_g(rows)
    out[:, 1:4] *= G0
    return out


def _gyro_plus(rows: np.ndarray) -> np.ndarray:
    out = rows.copy()
    out[:, 5] += 300.0  # a 16-bit gyro's zero not taken off: 300 deg/s at rest
    return out


def _sixteen_bit(rows: np.ndarray) -> np.ndarray:
    out = rows.copy()  # another sensor's counts: zero 32768, 16384 counts/g
    out[:, 1:4] = 32768.0 + (rows[:, 1:4] - ZERO) / PER_G * 16384.0
    return out


def _same(rows: np.ndarray) -> np.ndarray:
    return rows


Case = tuple[str, Callable[[np.ndarray], np.ndarray], tuple[str, ...], str]

CASES: list[Case] = [
    (
        "rate against the timestamps",
        _same,
        ("--rate", "20"),
        r"stream: --rate 20 samples/s, but the time column steps 0\.005 s \(200 samples/s\): "
        r"give that rate, or leave out --rate",
    ),
    (
        "deg/s declared rad/s",
        _same,
        ("--gyro-units", "rads"),
        rf"stream: the gyros turn {NUMBER} times as far as gravity turns between the poses "
        r"\(median of \d+ moves\): --gyro-units rads, but deg/s\? use --gyro-units dps",
    ),
    (
        "a whole turn declared that the recording lacks",
        _same,
        ("--known-turn-deg", "360"),
        r"whole turns of 360° declared, but no move that returns within 20° to the pose it "
        r"left sweeps within 25% of it \(theirs: none\): leave out --known-turn-deg, or "
        r"declare the angle the turns sweep",
    ),
    (
        "a gyro's 16-bit zero left on",
        _gyro_plus,
        (),
        rf"stream: gyro y reads \+{NUMBER} deg/s at rest, beyond the 50 deg/s a MEMS gyro's "
        r"bias reaches: an output's zero not taken off \(32768 of a 16-bit one\?\), or the "
        r"gyro units",
    ),
    (
        "counts declared m/s²",
        _same,
        ("--accel-units", "m/s2"),
        rf"stream: --accel-units m/s2, but the accelerometer reads {NUMBER} m/s² at rest: ADC "
        r"counts\? take off the sensor's zero, divide by its counts per g and use "
        r"--accel-units g \(the putter's own counts: --accel-units counts\)",
    ),
    (
        "m/s² declared g",
        _in_ms2,
        ("--accel-units", "g"),
        rf"stream: --accel-units g, but the accelerometer reads {NUMBER} g at rest: m/s²\? "
        r"use --accel-units m/s2",
    ),
    (
        "g declared m/s²",
        _in_g,
        ("--accel-units", "m/s2"),
        rf"stream: --accel-units m/s2, but the accelerometer reads {NUMBER} m/s² at rest: g\? "
        r"use --accel-units g",
    ),
    (
        "another sensor's counts taken for the putter's",
        _sixteen_bit,
        (),
        rf"stream: accelerometer reads {NUMBER} g at rest in the putter's counts \(zero 2048, "
        r"819\.2 counts/g\): another sensor's counts\? convert them to g and use "
        r"--accel-units g",
    ),
    (
        "seconds declared milliseconds",
        _same,
        ("--time-units", "ms"),
        r"stream: time steps 5e-06 s apart \(2e\+05 samples/s\): seconds\? use --time-units "
        r"s, or give the rate with --rate HZ",
    ),
]


@pytest.mark.parametrize(("name", "make", "declared", "refusal"), CASES, ids=[c[0] for c in CASES])
def test_a_declaration_the_data_contradicts_is_one_line_and_exit_2(
    run_cli: CliRunner,
    tmp_path: Path,
    rows: np.ndarray,
    name: str,
    make: Callable[[np.ndarray], np.ndarray],
    declared: tuple[str, ...],
    refusal: str,
) -> None:
    path = tmp_path / "log.csv"
    np.savetxt(path, make(rows), delimiter=",", header=HEADER, comments="", fmt="%.10g")
    result = run_cli("solve", str(path), "--stream", "--model", "nine", *declared)
    assert result.returncode == 2, (name, result.stdout, result.stderr)
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert re.fullmatch(rf"calstation: error: {re.escape(str(path))}: {refusal}", lines[0]), lines[
        0
    ]


def test_the_same_recording_declared_right_is_calibrated(
    run_cli: CliRunner, tmp_path: Path, rows: np.ndarray
) -> None:
    # Each refusal above is the declaration's, not the recording's: declared right (or
    # left to the defaults), the same data calibrates.
    path = tmp_path / "log.csv"
    np.savetxt(path, _in_ms2(rows), delimiter=",", header=HEADER, comments="", fmt="%.10g")
    result = run_cli(
        "solve", str(path), "--stream", "--model", "nine", "--accel-units", "m/s2", "--rate", "200"
    )
    assert result.returncode == 0, result.stderr


def test_a_wrong_rate_over_a_column_of_sample_numbers_is_caught_by_the_moves(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    # imucal's public session numbers its samples (no time to check a rate against):
    # declared at a tenth of its 102.4 samples/s, its moves sweep ten times too far.
    with gzip.open(FERRARIS, "rt") as src:
        header = src.readline().strip().split(",")
        table = np.loadtxt(src, delimiter=",")
    columns = ("n_samples", "acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z")
    path = tmp_path / "ferraris.csv"
    np.savetxt(
        path,
        table[:, [header.index(c) for c in columns]],
        delimiter=",",
        header=HEADER,
        comments="",
        fmt="%.17g",
    )
    result = run_cli("solve", str(path), "--stream", "--accel-units", "m/s2", "--rate", "10.24")
    assert result.returncode == 2
    assert result.stdout == ""
    assert re.fullmatch(
        rf"calstation: error: {re.escape(str(path))}: stream: the gyros turn {NUMBER} times "
        r"as far as gravity turns between the poses \(median of \d+ moves\): not deg/s \(raw "
        r"counts\?\): convert them to deg/s or rad/s \(or --rate 10\.24 wrong\)",
        result.stderr.strip(),
    ), result.stderr
