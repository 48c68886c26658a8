"""The ``calstation`` entry point itself: every command listed, none loaded to list it."""

import importlib
import inspect
import os
import subprocess
import sys

import pytest
import typer

from station import __version__
from station.cli.main import COMMANDS
from tests.conftest import REPO_ROOT, CliRunner

#: What a one-line answer must not wait for (issue 28): the numerics, the database and
#: web layers, the station's loop and the report renderer.
HEAVY = ("numpy", "scipy", "matplotlib", "sqlalchemy", "fastapi", "station.loop", "station.report")


def heavy_imports(*args: str) -> set[str]:
    """The heavy modules ``calstation ARGS`` imported, as ``python -X importtime`` lists them."""
    env = {**os.environ, "PYTHONPATH": str(REPO_ROOT)}
    result = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "station", *args],
        capture_output=True,
        text=True,
        env=env,
        check=False,
        timeout=120,
    )
    names = {
        line.rsplit("|", 1)[1].strip()
        for line in result.stderr.splitlines()
        if line.startswith("import time:") and "|" in line
    }
    assert names, result.stderr  # the listing itself is there
    return {n for n in names for h in HEAVY if n == h or n.startswith(f"{h}.")}


@pytest.mark.parametrize("args", [("--help",), ("version",), ("no-such-command",), ()], ids=str)
def test_one_line_answers_load_none_of_the_heavy_libraries(args: tuple[str, ...]) -> None:
    assert heavy_imports(*args) == set()


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


@pytest.mark.parametrize("name", COMMANDS)
def test_the_help_lists_each_command_by_its_own_summary(name: str) -> None:
    module, attribute, summary = COMMANDS[name]
    target = getattr(importlib.import_module(module), attribute)
    own = target.info.help if isinstance(target, typer.Typer) else inspect.getdoc(target)
    assert isinstance(own, str)
    assert " ".join(own.split("\n\n")[0].split()) == summary
