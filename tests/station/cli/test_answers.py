"""The command line answers bad input in one line a person reads, exit status 2, and its
help names each flag as it is typed: the real ``calstation`` process (``run_cli``)."""

import os
from pathlib import Path

import pytest

from station.results.outbox import Outbox
from tests.conftest import CliRunner
from tests.db.records import make_record


def _env(**variables: str) -> dict[str, str]:
    clean = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    return {**clean, **variables}


REVIEW = ("review", "PT000001", "--decision", "retest", "--root-cause", "a", "--repair", "b")


@pytest.mark.parametrize(
    ("args", "said"),
    [
        (
            (*REVIEW, "--by", "qa kim"),
            "calstation review: Invalid value for '--by': 'qa kim' is refused: a name is 1 to "
            "64 letters, digits and . _ : @ -, no spaces, starting with a letter or digit "
            "(e.g. qa.kim) (see calstation review --help)",
        ),
        (
            ("review", "PT000001", "--by", "qa.kim"),
            "calstation review: Missing option '--decision'. Choose from: retest, scrap (see "
            "calstation review --help)",
        ),
        (
            ("demo", "--units", "0"),
            "calstation demo: Invalid value for '--units': Input should be greater than or "
            "equal to 1 (see calstation demo --help)",
        ),
        (
            ("solve", "--bogus"),
            "calstation solve: No such option: --bogus (see calstation solve --help)",
        ),
        (("nosuch",), "calstation: No such command 'nosuch'. (see calstation --help)"),
    ],
)
def test_a_refused_command_line_is_one_line_and_exit_2(
    run_cli: CliRunner, args: tuple[str, ...], said: str
) -> None:
    result = run_cli(*args, env=_env())
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr == f"calstation: error: {said}\n"


@pytest.mark.parametrize("command", [("demo",), ("review",), ("outbox", "list"), ()])
def test_the_help_names_each_flag_as_it_is_typed(
    run_cli: CliRunner, command: tuple[str, ...]
) -> None:
    result = run_cli(*command, "--help", env=_env())
    assert result.returncode == 0, result.stderr
    assert "<bool>" not in result.stdout
    assert "╭" not in result.stdout
    help_line = [line for line in result.stdout.splitlines() if line.strip().startswith("--help")]
    assert [line.split() for line in help_line] == [
        ["--help", "Show", "this", "message", "and", "exit."]
    ]


def test_a_group_without_its_command_shows_its_help(run_cli: CliRunner) -> None:
    result = run_cli("db", env=_env())
    assert result.returncode == 2
    assert result.stdout.startswith("Usage: calstation db [OPTIONS] COMMAND [ARGS]...")
    assert "upgrade" in result.stdout


def test_outbox_list_sets_a_torn_file_aside_with_its_reason(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    outbox = Outbox(tmp_path / "data" / "outbox")
    outbox.put(make_record(serial="PT000003"))
    torn = outbox.directory / "torn.json"
    torn.write_text('{"run_id": "torn", "serial": "PT0000')
    result = run_cli("outbox", "list", env=_env(CALSTATION_DATA_DIR=str(tmp_path / "data")))
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].split()[::2] == ["waiting", "PT000003"]
    assert lines[1].startswith("unreadable  torn ")
    assert "not JSON" in lines[1]
    assert lines[2] == f"1 waiting, 1 unreadable, 0 refused in {outbox.directory}"
    assert not torn.exists()
    assert (outbox.unreadable_dir / "torn.json").exists()
