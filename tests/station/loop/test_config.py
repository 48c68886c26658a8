"""Station configuration: file, environment and flags; bad values named."""

from pathlib import Path

import pytest

from station.domain.errors import InputError
from station.loop.config import load_config
from tests.conftest import CliRunner


def test_flags_override_the_file_and_the_environment(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "station.toml"
    path.write_text(
        'station_id = "line1-st3"\noperator_id = "ann"\n[run]\npose_tolerance_deg = 20\n'
    )
    monkeypatch.setenv("CALSTATION_OPERATOR_ID", "bob")
    config = load_config(path, {"operator_id": "carl", "port": None, "lot": "L2611-04"})
    assert config.lot == "L2611-04"
    assert config.station_id == "line1-st3"
    assert config.operator_id == "carl"
    assert config.run.pose_tolerance_deg == 20
    assert config.journal_path.name == "journal-line1-st3.json"


def test_a_commands_defaults_stand_only_for_what_nothing_else_names(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "station.toml"
    path.write_text('station_id = "line1-st3"\n')
    monkeypatch.setenv("CALSTATION_OPERATOR_ID", "bob")
    demo = {"station_id": "demo-station", "operator_id": "demo-operator", "lot": "demo-lot"}
    config = load_config(path, {"lot": None}, demo)
    assert (config.station_id, config.operator_id, config.lot) == ("line1-st3", "bob", "demo-lot")
    flagged = load_config(path, {"station_id": "st-9", "lot": "L7"}, demo)
    assert (flagged.station_id, flagged.lot) == ("st-9", "L7")
    monkeypatch.delenv("CALSTATION_OPERATOR_ID")
    bare = load_config(None, {}, demo)
    assert (bare.station_id, bare.operator_id, bare.lot) == (
        "demo-station",
        "demo-operator",
        "demo-lot",
    )


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ('[run]\nposes = ["face_up", "head_up"]\n', "run.poses"),
        (
            '[run]\nposes = ["face_up", "face_down", "toe_up", "toe_down", "shaft_up", '
            '"head_up"]\n',
            "head_up",
        ),
        ('serial_pattern = "(["\n', "serial_pattern: not a regular expression"),
        # Read by RE2 (linear time): what needs backtracking is refused at start-up.
        ("serial_pattern = '^(P)\\1$'\n", "serial_pattern: not a regular expression the station"),
        (
            "[label]\npattern = '(?P<serial>PT\\d+)(?=/)'\n",
            "label: pattern is not a regular expression the station reads",
        ),
        ('station_id = "has space"\n', "station_id"),
        ('lot = "L 7"\n', "lot"),
        ("bogus = 1\n", "bogus"),
        ("not toml [", "not valid TOML"),
    ],
)
def test_bad_configuration_is_one_line_naming_the_field(
    run_cli: CliRunner, tmp_path: Path, content: str, message: str
) -> None:
    path = tmp_path / "station.toml"
    path.write_text(content)
    with pytest.raises(InputError, match=message.replace("[", r"\[").replace("(", r"\(")):
        load_config(path, {})
    result = run_cli("run", "--config", str(path), "--port", "/dev/null")
    assert result.returncode == 2
    assert len(result.stderr.strip().splitlines()) == 1
    assert str(path) in result.stderr


def test_the_whole_unit_profile_chooses_its_run_plan_and_the_file_still_wins(
    tmp_path: Path,
) -> None:
    default = load_config(None, {})
    assert (len(default.run.poses), default.run.model, default.run.gyro) == (6, "six", False)
    whole = load_config(None, {"limits_profile": "whole-unit"})
    assert (len(whole.run.poses), whole.run.model, whole.run.gyro) == (12, "nine", True)
    path = tmp_path / "station.toml"
    path.write_text('limits_profile = "whole-unit"\n[run]\npose_tolerance_deg = 20\n')
    config = load_config(path, {})
    assert (config.run.pose_tolerance_deg, config.run.gyro) == (20, True)


def test_the_gyro_matrix_with_the_six_parameter_model_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "station.toml"
    path.write_text('limits_profile = "whole-unit"\n[run]\nmodel = "six"\n')
    with pytest.raises(InputError, match="gyro: the gyro matrix needs model = 'nine'"):
        load_config(path, {})
