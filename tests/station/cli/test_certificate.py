"""``calstation certificate``: the station's own certificate of a unit it calibrated,
end to end: a demo station reads each virtual putter's coefficients before it writes its
own, and the certificate states them as found beside what it left."""

import json
import os
import sqlite3
from pathlib import Path

import pytest

from station.report.formatting import number
from tests.conftest import CliRunner

STATION = """station_id = "line2-st9"
operator_id = "qa-ann"

[laboratory]
name = "Putter Works Calibration Lab"
address = "12 Gangnam-daero, Seoul"
location = "line 2"
customer = "Putter Works Quality"
gravity_m_s2 = 9.79966
traceability = "g from the plant's absolute gravity survey"
"""


def _env(tmp: Path) -> dict[str, str]:
    env = {**os.environ, "CALSTATION_DATA_DIR": str(tmp)}
    for name in ("CALSTATION_DATABASE_URL", "CALSTATION_STATION_ID", "CALSTATION_OPERATOR_ID"):
        env.pop(name, None)
    return env


@pytest.mark.timeout(240)
def test_the_station_s_own_certificate_states_its_lab_and_the_unit_as_found_and_left(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    config = tmp_path / "station.toml"
    config.write_text(STATION)
    args = ("demo", "--units", "1", "--json", "--speed", "20", "--config", str(config))
    result = run_cli(*args, env=_env(tmp_path), timeout=180)
    assert result.returncode == 0, result.stderr
    [unit] = json.loads(result.stdout)
    with sqlite3.connect(tmp_path / "calstation.sqlite3") as db:
        [(stored,)] = db.execute("select as_found from runs").fetchall()
    found = json.loads(stored)
    # The station read what the virtual putter held before it wrote its own: a unit
    # leaves its maker unwritten, holding the nominal zero; no gyros read (not a
    # whole-unit run).
    assert found["accelerometer"]["written"] is False
    assert found["accelerometer"]["offset"] == [2048.0, 2048.0, 2048.0]
    assert found.get("gyro") is None

    out = tmp_path / "certificate.html"
    args = ("certificate", "issue", unit["serial"], "--config", str(config), "--out", str(out))
    result = run_cli(*args, env=_env(tmp_path))
    assert result.returncode == 0, result.stderr
    page = out.read_text()
    assert "Putter Works Calibration Lab" in page
    assert "line 2, station line2-st9" in page
    assert "held its factory defaults (never calibrated)" in page
    as_found = page.split('class="coefficient-state as-found"')[1].split("</table>")[0]
    assert f"<td>{number(2048.0, 8)}</td>" in as_found
    assert 'class="coefficient-state as-left"' in page
    assert "— end of certificate —" in page


@pytest.mark.parametrize(
    ("args", "line"),
    [
        (("PT999999",), "no calibration run of serial 'PT999999'"),
        (("PT000001", "--language", "fr"), "--language 'fr' is not one of en, ko, zh"),
        (("PT000001", "--config", "/nonexistent.toml"), "cannot read the laboratory"),
    ],
)
def test_a_certificate_that_cannot_be_issued_is_one_line_and_exit_2(
    run_cli: CliRunner, tmp_path: Path, args: tuple[str, ...], line: str
) -> None:
    result = run_cli("certificate", "issue", *args, env=_env(tmp_path))
    assert result.returncode == 2
    assert line in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
