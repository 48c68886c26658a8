"""The ``calstation`` entry point itself."""

from station import __version__
from station.cli.main import COMMANDS
from tests.conftest import CliRunner


def test_version_prints_the_package_version(run_cli: CliRunner) -> None:
    result = run_cli("version")
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == __version__


def test_unknown_command_is_a_usage_error(run_cli: CliRunner) -> None:
    result = run_cli("no-such-command")
    assert result.returncode == 2
    assert "no-such-command" in result.stderr


def test_every_command_is_listed_in_the_help(run_cli: CliRunner) -> None:
    result = run_cli("--help")
    assert result.returncode == 0, result.stderr
    for name in [*COMMANDS, "version"]:
        assert f" {name} " in result.stdout, name
