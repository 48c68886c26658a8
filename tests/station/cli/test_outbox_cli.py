"""``calstation outbox``: list, show, resend and send what was set aside, through its entry
point in the test's process (``call_cli``)."""

import os
from pathlib import Path
from uuid import uuid4

import pytest
from sqlalchemy import select

from db import Database
from db.models import Run
from db.store.repository import RunRepository
from station.results.outbox import Outbox
from station.results.storage import DatabaseStore, HttpStore
from tests.conftest import CliRunner
from tests.db.records import make_record
from tests.servers import STATION


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


def test_list_names_every_run_and_why_it_was_set_aside(call_cli: CliRunner, outbox: Outbox) -> None:
    result = call_cli("outbox", "list", env=env(outbox))
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0].split()[::2] == ["waiting", "PT000003"]
    assert lines[1].startswith("unreadable  torn ")
    assert "not JSON" in lines[1]
    assert lines[2].split()[::2][:2] == ["refused", "PT000001"]
    assert lines[2].endswith("is already stored with different content")
    assert lines[3] == f"1 waiting, 1 unreadable, 1 refused in {outbox.directory}"


def test_show_gives_the_record_and_the_reason(call_cli: CliRunner, outbox: Outbox) -> None:
    refused = next(outbox.refused_dir.glob("*.json"))
    result = call_cli("outbox", "show", refused.stem[:8], env=env(outbox))
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith(f"refused: {refused}\nreason: ")
    assert '"operator_id": "someone-else"' in result.stdout
    unknown = call_cli("outbox", "show", "PT999999", env=env(outbox))
    assert unknown.returncode == 2
    assert unknown.stderr == "calstation: error: no run 'PT999999' in " + (
        f"{outbox.directory} (see calstation outbox list)\n"
    )


def test_resend_puts_back_what_reads_and_keeps_what_does_not(
    call_cli: CliRunner, outbox: Outbox
) -> None:
    torn = outbox.unreadable_dir / "torn.json"
    result = call_cli("outbox", "resend", "--all", env=env(outbox))
    assert result.returncode == 0, result.stderr
    assert "run torn still unreadable (not JSON" in result.stdout
    assert result.stdout.endswith("1 run back in the outbox\n")
    assert torn.exists()
    assert outbox.set_aside() == (1, 0)
    assert outbox.count() == 2
    single = call_cli("outbox", "resend", "torn", env=env(outbox))
    assert (single.returncode, single.stdout) == (2, "")
    assert "still unreadable" in single.stderr
    torn.write_text(make_record(serial="PT000004").model_dump_json())  # repaired by hand
    repaired = call_cli("outbox", "resend", "torn", env=env(outbox))
    assert repaired.returncode == 0, repaired.stderr
    assert outbox.set_aside() == (0, 0)
    assert outbox.count() == 3
    assert not list(outbox.unreadable_dir.glob("*.txt"))


@pytest.mark.parametrize("args", [(), ("PT000003", "--all")])
def test_resend_with_bad_input_is_one_line_and_exit_2(
    call_cli: CliRunner, outbox: Outbox, args: tuple[str, ...]
) -> None:
    result = call_cli("outbox", "resend", *args, env=env(outbox))
    assert result.returncode == 2
    assert len(result.stderr.splitlines()) == 1
    assert result.stderr.startswith("calstation: error: ")


def test_a_renamed_stations_queued_run_is_set_aside_and_sent_with_its_own_key(
    call_cli: CliRunner, tmp_path: Path, live_url: str, database: Database, station_key: str
) -> None:
    """A run queued under the station's former name used to get 403 (read as
    a bad key, "fix api_key") and stop every run behind it, forever."""
    outbox = Outbox(tmp_path / "data" / "outbox")
    former = make_record(serial="PT000010", station_id="line0-old")
    outbox.put(former)
    current = make_record(serial="PT000011", station_id=STATION)
    outbox.put(current)
    with HttpStore(live_url, station_key, station_id=STATION) as store:
        result = outbox.sync(store)
    assert (result.stored, result.refused, result.pending, result.error) == (1, 1, 0, None)
    listed = call_cli("outbox", "list", env=env(outbox))
    assert listed.returncode == 0, listed.stderr
    refused = listed.stdout.splitlines()[0]
    assert refused.split()[:3] == ["refused", str(former.run_id), "PT000010"]
    assert refused.endswith(
        f"only a key of line0-old can store it (calstation outbox send {former.run_id} "
        "--api-key KEY)"
    )
    with database.session() as session, session.begin():
        former_key = RunRepository(session).create_key("line0-old")
    wrong = call_cli(
        "outbox",
        "send",
        str(former.run_id),
        "--api-key",
        station_key,
        "--server",
        live_url,
        env=env(outbox),
    )
    assert wrong.returncode == 2
    assert wrong.stderr.startswith(f"calstation: error: run {former.run_id} not stored: ")
    assert "belongs to station line1-st1, the run to line0-old" in wrong.stderr
    sent = call_cli(
        "outbox",
        "send",
        str(former.run_id)[:8],
        "--api-key",
        former_key,
        "--server",
        live_url,
        env=env(outbox),
    )
    assert sent.returncode == 0, sent.stderr
    assert sent.stdout == f"run {former.run_id} stored (refused before)\n"
    assert not any(outbox.refused_dir.iterdir())
    with database.session() as session:
        stored = session.execute(
            select(Run.run_id, Run.station_id).where(
                Run.run_id.in_([former.run_id, current.run_id])
            )
        )
        assert {run_id: station for run_id, station in stored} == {
            former.run_id: "line0-old",
            current.run_id: STATION,
        }
