"""``calstation outbox``: list, show and resend what the outbox set aside, as real processes."""

import os
from pathlib import Path
from uuid import uuid4

import pytest

from station.results.outbox import Outbox
from station.results.storage import DatabaseStore
from tests.conftest import CliRunner
from tests.db.records import make_record


@pytest.fixture
def outbox(tmp_path: Path, sqlite_url: str) -> Outbox:
    """An outbox holding one run waiting, one refused (a clashing id), one unreadable."""
    outbox = Outbox(tmp_path / "data" / "outbox")
    stored = make_record(serial="PT000001", run_id=uuid4())
    with DatabaseStore(sqlite_url) as store:
        store.submit(stored)
        outbox.put(stored.model_copy(update={"operator_id": "someone-else"}))  # same id
        (outbox.directory / "torn.json").write_text('{"run_id": "torn", "serial": "PT0000')
        assert outbox.sync(store).refused == 1
    outbox.put(make_record(serial="PT000003"))
    return outbox


def env(outbox: Outbox) -> dict[str, str]:
    clean = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    return {**clean, "CALSTATION_DATA_DIR": str(outbox.directory.parent)}


def test_list_names_every_run_and_why_it_was_set_aside(run_cli: CliRunner, outbox: Outbox) -> None:
    result = run_cli("outbox", "list", env=env(outbox))
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].split()[::2] == ["waiting", "PT000003"]
    assert lines[1].startswith("unreadable  torn ")
    assert "not JSON" in lines[1]
    assert lines[2].split()[::2][:2] == ["refused", "PT000001"]
    assert lines[2].endswith("is already stored with different content")
    assert lines[3] == f"1 waiting, 1 unreadable, 1 refused in {outbox.directory}"


def test_show_gives_the_record_and_the_reason(run_cli: CliRunner, outbox: Outbox) -> None:
    refused = next(outbox.refused_dir.glob("*.json"))
    result = run_cli("outbox", "show", refused.stem[:8], env=env(outbox))
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"refused: {refused}\nreason: ")
    assert '"operator_id": "someone-else"' in result.stdout
    unknown = run_cli("outbox", "show", "PT999999", env=env(outbox))
    assert unknown.returncode == 2
    assert unknown.stderr == "calstation: error: no run 'PT999999' in " + (
        f"{outbox.directory} (see calstation outbox list)\n"
    )


def test_resend_puts_back_what_reads_and_keeps_what_does_not(
    run_cli: CliRunner, outbox: Outbox
) -> None:
    torn = outbox.unreadable_dir / "torn.json"
    result = run_cli("outbox", "resend", "--all", env=env(outbox))
    assert result.returncode == 0, result.stderr
    assert "run torn still unreadable (not JSON" in result.stdout
    assert result.stdout.endswith("1 run back in the outbox\n")
    assert torn.exists()
    assert outbox.set_aside() == (1, 0)
    assert outbox.count() == 2
    single = run_cli("outbox", "resend", "torn", env=env(outbox))
    assert (single.returncode, single.stdout) == (2, "")
    assert "still unreadable" in single.stderr
    torn.write_text(make_record(serial="PT000004").model_dump_json())  # repaired by hand
    repaired = run_cli("outbox", "resend", "torn", env=env(outbox))
    assert repaired.returncode == 0, repaired.stderr
    assert outbox.set_aside() == (0, 0)
    assert outbox.count() == 3
    assert not list(outbox.unreadable_dir.glob("*.txt"))


@pytest.mark.parametrize("args", [(), ("PT000003", "--all")])
def test_resend_with_bad_input_is_one_line_and_exit_2(
    run_cli: CliRunner, outbox: Outbox, args: tuple[str, ...]
) -> None:
    result = run_cli("outbox", "resend", *args, env=env(outbox))
    assert result.returncode == 2
    assert len(result.stderr.splitlines()) == 1
    assert result.stderr.startswith("calstation: error: ")
