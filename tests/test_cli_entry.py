"""The ``calstation`` entry point itself: every command listed, none loaded to list it."""

import importlib
import inspect
import json
import os
import subprocess
import sys
from typing import Any

import pytest
import typer

from station import __version__
from station.cli.main import COMMANDS
from tests.conftest import REPO_ROOT, CliRunner, computed_once
from tests.forked_cli import HEAVY


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
    "db partitions": ("--ahead", "-1"),
    "db backup": (),
    "db restore": ("line.backup", "--replace", "x"),
    "keys create": ("--station", "not a name"),
    "keys revoke": ("--lab", "not/a/name"),
    "certificate issue": ("--no-such-option",),
    "certificate signatory": ("ann",),
    "certificate sign": ("PT000001",),
    "certificate verify": (),
    "outbox list": ("--no-such-option",),
    "outbox show": (),
    "outbox resend": ("--all", "--no-such-option"),
    "outbox send": ("RUN", "--api-key"),
}


def test_every_command_has_an_argument_it_refuses() -> None:
    assert sorted(REFUSED) == sorted(LEAVES)


def _help(command: str) -> list[str]:
    return [*command.split(), "--help"]


def _refused(command: str) -> list[str]:
    return [*command.split(), *REFUSED[command]]


@pytest.fixture(scope="module")
def forked(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """Every command's help and refused argument, each in a process forked from one that
    loaded only the entry point (:mod:`tests.forked_cli`): its exit status and the heavy
    modules it loaded; run once for all workers. The entry point's own imports are the
    one-line answers' test, in processes of their own."""
    found = computed_once(tmp_path_factory, "forked-cli", _run_forked)
    assert isinstance(found, dict)
    return found


def _run_forked() -> dict[str, Any]:
    lines = [_help(c) for c in EVERY_COMMAND] + [_refused(c) for c in REFUSED]
    result = subprocess.run(
        [sys.executable, "-m", "tests.forked_cli"],
        input=json.dumps(lines),
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(REPO_ROOT)},
        cwd=REPO_ROOT,
        check=False,
        timeout=300,
    )
    assert result.returncode == 0, result.stderr
    answer = json.loads(result.stdout)
    assert answer["base"] == []  # so what each run loaded on top is all it loaded
    return {" ".join(args): run for args, run in zip(lines, answer["runs"], strict=True)}


@pytest.mark.parametrize("command", EVERY_COMMAND)
def test_a_commands_help_loads_none_of_the_heavy_libraries(
    command: str, forked: dict[str, Any]
) -> None:
    assert forked[" ".join(_help(command))] == {"status": 0, "heavy": []}


@pytest.mark.parametrize("command", REFUSED)
def test_a_refused_argument_loads_none_of_the_heavy_libraries(
    command: str, forked: dict[str, Any]
) -> None:
    # Refused as a usage error, before anything heavy is loaded.
    assert forked[" ".join(_refused(command))] == {"status": 2, "heavy": []}


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
