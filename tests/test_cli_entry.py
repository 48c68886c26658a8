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


def _subcommands(group: str) -> list[str]:
    """The subcommands of ``group``, as typed after ``calstation``; none for a command."""
    module, attribute, _ = COMMANDS[group]
    target = getattr(importlib.import_module(module), attribute)
    if not isinstance(target, typer.Typer):
        return []
    return [
        f"{group} {info.name or typer.main.get_command_name(info.callback.__name__)}"
        for info in target.registered_commands
        if info.callback is not None
    ]


SUBCOMMANDS = {name: _subcommands(name) for name in COMMANDS}
#: Every command, group and subcommand, as typed after ``calstation``.
EVERY_COMMAND = [name for group, subs in SUBCOMMANDS.items() for name in [group, *subs]]
#: The ones that run (a group only lists its subcommands).
LEAVES = [name for name in EVERY_COMMAND if not SUBCOMMANDS.get(name)]

#: An argument each command refuses before it runs (exit status 2, a usage error).
REFUSED = {
    "run": ("--units", "x"),
    "demo": ("--units", "x"),
    "solve": ("poses.csv", "--model", "ten"),
    "simulate": ("--rate", "x"),
    "serve": ("--port", "0"),
    "report": ("--units", "0"),
    "review": ("PT000001", "--decision", "keep"),
    "gyro fit": ("log.csv", "--alpha", "x"),
    "gyro check": (),
    "gyro simulate-centrifuge": ("--seed", "x"),
    "db upgrade": ("--no-such-option",),
    "db rebuild-report": ("--no-such-option",),
    "keys create": ("--station", "not a name"),
    "keys revoke": ("--lab", "not/a/name"),
    "outbox list": ("--no-such-option",),
    "outbox show": (),
    "outbox resend": ("--all", "--no-such-option"),
    "outbox send": ("RUN", "--api-key"),
}


def test_every_command_has_an_argument_it_refuses() -> None:
    assert sorted(REFUSED) == sorted(LEAVES)


@pytest.mark.parametrize("command", EVERY_COMMAND)
def test_a_commands_help_loads_none_of_the_heavy_libraries(command: str) -> None:
    assert heavy_imports(*command.split(), "--help") == set()


@pytest.mark.parametrize("command", REFUSED)
def test_a_refused_argument_loads_none_of_the_heavy_libraries(
    command: str, run_cli: CliRunner
) -> None:
    args = (*command.split(), *REFUSED[command])
    assert run_cli(*args).returncode == 2  # refused, as a usage error
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
