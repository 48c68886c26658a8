"""``calstation report`` through its entry point in the test's process (``call_cli``), on
both backends."""

import json
import os
from importlib import resources
from pathlib import Path

import pytest

from db import Database
from tests.conftest import CliRunner
from tests.db.eol_data import RUNS, insert_line_history

RANGE = ("--from", "2026-11-02T08:00Z", "--to", "2026-11-02T10:00Z")


def _env(**variables: str) -> dict[str, str]:
    clean = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    return {**clean, **variables}


@pytest.fixture
def line(database: Database) -> None:
    with database.session() as session:
        insert_line_history(session)


@pytest.mark.usefixtures("line")
def test_text_report_reads_the_database_from_the_environment(
    call_cli: CliRunner, database_url: str
) -> None:
    result = call_cli("report", *RANGE, env=_env(CALSTATION_DATABASE_URL=database_url))
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].startswith("End-of-line report (from 2026-11-02 08:00:00 UTC")
    all_row = next(line for line in lines if line.startswith("all "))
    # units, passed, failed, runs, report yield, first-pass yield, final yield
    assert all_row.split()[1:11] == ["5", "3", "2", "7", "42.9", "%", "40.0", "%", "60.0", "%"]
    assert any(line.split()[:2] == ["U3", "hold"] for line in lines)


@pytest.mark.usefixtures("line")
def test_json_to_a_file_with_station_and_operator_filters(
    call_cli: CliRunner, database_url: str, tmp_path: Path
) -> None:
    target = tmp_path / "eol.json"
    result = call_cli(
        "report",
        *RANGE,
        "--station",
        "st1",
        "--operator",
        "op-a",
        "--format",
        "json",
        "--out",
        str(target),
        "--database-url",
        database_url,
        env=_env(),
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""
    report = json.loads(target.read_text())
    # st1 by op-a: U1 pass; U2 fail then pass.
    assert (report["summary"]["runs"], report["summary"]["first_pass_units"]) == (3, 1)
    assert report["filter"]["operator_id"] == "op-a"


@pytest.mark.usefixtures("line")
def test_lot_filter_leaves_out_the_runs_without_a_lot(
    call_cli: CliRunner, database_url: str
) -> None:
    result = call_cli("report", *RANGE, "--lot", "L-7", "--database-url", database_url, env=_env())
    assert result.returncode == 0, result.stderr
    assert "lot L-7" in result.stdout.splitlines()[0]
    all_row = next(line for line in result.stdout.splitlines() if line.startswith("all "))
    assert all_row.split()[1:5] == ["0", "0", "0", "0"]


@pytest.mark.usefixtures("line")
def test_the_widest_period_is_reported(call_cli: CliRunner, database_url: str) -> None:
    result = call_cli(
        "report", "--from", "0001-01-02", "--to", "9999-12-31", "--database-url", database_url
    )
    assert result.returncode == 0, result.stderr
    all_row = next(line for line in result.stdout.splitlines() if line.startswith("all "))
    # Every run of the history: the one after the usual range too.
    units, runs = all_row.split()[1], all_row.split()[4]
    assert (int(units), int(runs)) == (len({run[1] for run in RUNS}), len(RUNS))


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        (("--from", "yesterday"), "--from 'yesterday' is not an ISO date"),
        (("--format", "xml"), "--format 'xml' is not one of text, csv, json, html"),
        (("--limits", "/nonexistent/limits.toml"), "cannot read the limits file"),
        (("--timezone", "Mars/Olympus"), "time zone 'Mars/Olympus' is unknown"),
        (("--shifts", "06:00,6pm"), "shift start '6pm' is not a time of day"),
        (("--from", "9999-12-31T23:00:00-05:00"), "--from '9999-12-31T23:00:00-05:00' is out of"),
        (("--to", "0001-01-01T00:00:00+01:00"), "--to '0001-01-01T00:00:00+01:00' is out of"),
        (
            ("--from", "2026-02-01", "--to", "2026-01-01"),
            "--from 2026-02-01 00:00+00:00 is not before --to",
        ),
    ],
)
def test_bad_options_are_one_line_and_exit_2(
    call_cli: CliRunner, tmp_path: Path, arguments: tuple[str, ...], message: str
) -> None:
    result = call_cli("report", *arguments, env=_env(CALSTATION_DATA_DIR=str(tmp_path)))
    assert result.returncode == 2
    assert result.stderr.startswith("calstation: error: ")
    assert message in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize("command", [("report",), ("solve", "poses.csv")])
def test_a_limits_file_with_a_huge_integer_is_one_line_and_exit_2(
    run_cli: CliRunner, tmp_path: Path, command: tuple[str, ...]
) -> None:
    """An integer of 4 301 digits is more than Python converts: the TOML reader's
    ValueError is the file's problem, named in one line, never a traceback."""
    limits = tmp_path / "big.toml"
    limits.write_text('[profiles.big]\nversion = "1"\nretest_limit = ' + "9" * 4301 + "\n")
    (tmp_path / "poses.csv").write_text("ax,ay,az\n2031,1999,1143\n")
    result = run_cli(
        *command, "--limits", str(limits), cwd=tmp_path, env=_env(CALSTATION_DATA_DIR=str(tmp_path))
    )
    assert result.returncode == 2, result.stderr
    assert result.stderr.startswith("calstation: error: "), result.stderr
    assert f"{limits}: not valid TOML: Exceeds the limit (4300 digits)" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


@pytest.mark.usefixtures("line")
def test_the_plants_time_zone_reads_the_bounds_and_counts_its_days(
    call_cli: CliRunner, database_url: str
) -> None:
    """UTC+14: the history's runs (08:00–09:00 and 13:00 UTC on 11-02) are 22:00–23:00
    on 11-02 and 03:00 on 11-03 in the plant; its 11-03 holds U9's run only."""
    result = call_cli(
        "report",
        "--from",
        "2026-11-03",
        "--format",
        "json",
        "--database-url",
        database_url,
        env=_env(CALSTATION_PLANT_TIMEZONE="Pacific/Kiritimati"),
    )
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert report["timezone"] == "Pacific/Kiritimati"
    assert report["filter"]["since"].startswith("2026-11-02T10:00:00")
    assert [(d["day"], d["runs"]) for d in report["trend"]] == [("2026-11-03", 1)]


@pytest.mark.usefixtures("line")
def test_the_plants_shifts_give_a_trend_per_shift(call_cli: CliRunner, database_url: str) -> None:
    result = call_cli(
        "report",
        *RANGE,
        "--database-url",
        database_url,
        env=_env(CALSTATION_PLANT_SHIFTS="06:00,08:30,22:00"),
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    head = lines.index(
        "Trend per shift (UTC; shifts start at 06:00, 08:30, 22:00 and belong to the day "
        "they start on)"
    )
    # 08:00–08:20 in the 06:00 shift (U1, U2, U3), 08:30–09:00 in the 08:30 one (U4, U5).
    rows = {line.split()[1]: line.split()[2] for line in lines[head + 3 : head + 5]}
    assert rows == {"06:00": "3", "08:30": "2"}


@pytest.mark.usefixtures("line")
def test_limits_re_judge_the_runs_beside_the_current_figures(
    call_cli: CliRunner, database_url: str, tmp_path: Path
) -> None:
    shipped = resources.files("station.domain.profiles").joinpath("limits.toml")
    candidate = tmp_path / "candidate.toml"
    candidate.write_text(
        shipped.read_text(encoding="utf-8").replace(
            "offset_counts = { lower = 1841.0, upper = 2255.0 }",
            "offset_counts = { lower = 1841.0, upper = 2047.0 }",
        ),
        encoding="utf-8",
    )
    result = call_cli(
        "report", *RANGE, "--limits", str(candidate), "--database-url", database_url, env=_env()
    )
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert any(
        line.startswith("What-if: the runs re-judged against kxm52-production") for line in lines
    )
    # Offsets up to 2047: every run's offset y is 2048, so the 3 passing runs would fail.
    row = next(line for line in lines if line.startswith("runs passed"))
    assert row.split()[2:] == ["3", "0"]
    would_fail = next(line for line in lines if line.startswith("runs that would fail"))
    assert would_fail.split()[-1] == "3"
