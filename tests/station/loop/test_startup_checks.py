"""The start-up checks in process: ports, configuration values, unreadable journals."""

import json
import re
from datetime import UTC, datetime
from pathlib import Path
from uuid import uuid4

import pytest
from hypothesis import given
from hypothesis import strategies as st

from db.settings import check_database_url
from station.domain.errors import InputError
from station.domain.product.pose_plan import check_plan
from station.domain.signals.orientation import angle_deg
from station.domain.signals.poses import CALIBRATION_POSES, POSES, VERIFICATION_POSE, pose
from station.loop.config import load_config
from station.loop.startup import check_port
from station.results.journal import DiscardedJournal, JournalFile, RunJournal
from tests.conftest import CliRunner


@pytest.mark.parametrize(
    ("port", "message"),
    [
        (None, "no putter port"),
        ("/nonexistent/ttyUSB9", "port /nonexistent/ttyUSB9: no such device"),
        ("/etc/hostname", "port /etc/hostname: not a serial device"),
        ("socket://fixture", "expected socket://HOST:PORT"),
        ("socket://fixture:99999", "expected socket://HOST:PORT"),
        ("rfc2217://:4001", "expected rfc2217://HOST:PORT"),
        ("sokcet://fixture:4001", "protocol 'sokcet' not known"),
    ],
)
def test_a_port_that_cannot_be_one_is_refused(port: str | None, message: str) -> None:
    with pytest.raises(InputError, match=message):
        check_port(port)


@pytest.mark.parametrize("port", ["/dev/null", "socket://127.0.0.1:1", "loop://"])
def test_a_port_that_may_answer_later_is_accepted(port: str) -> None:
    check_port(port)  # a server that refuses now is told at start, not fatal


@pytest.mark.parametrize(
    ("url", "message"),
    [
        ("postgress://db/calstation", "unknown scheme 'postgress'"),
        ("mysql://db/calstation", "database 'mysql' is not supported"),
        ("postgresql+asyncpg://db/calstation", "the driver of 'postgresql+asyncpg' is not"),
        ("db.line1:5432", "not a database URL"),
    ],
)
def test_a_database_url_that_cannot_be_opened_is_refused(url: str, message: str) -> None:
    with pytest.raises(ValueError, match=re.escape(message)):
        check_database_url(url)
    with pytest.raises(
        InputError, match=f"^station configuration: database_url: {re.escape(message)}"
    ):
        load_config(None, {"database_url": url})


def test_the_supported_database_urls_are_accepted() -> None:
    for url in ("postgresql+psycopg://calstation@db/cal", "postgresql://u@h/d", "sqlite:///x.db"):
        assert check_database_url(url) == url


@pytest.mark.parametrize(
    ("values", "message"),
    [
        ({"server_url": "http://results:8000"}, "server_url needs the station's api_key"),
        ({"server_url": "results:8000", "api_key": "k"}, "server_url: 'results:8000' is not an"),
    ],
)
def test_a_server_needs_a_url_and_a_key(values: dict[str, str], message: str) -> None:
    with pytest.raises(InputError, match=message):
        load_config(None, values)


def test_the_environment_json_is_named(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("CALSTATION_RUN", '{"poses": ')
    with pytest.raises(InputError, match=r"^station configuration: CALSTATION_RUN: not valid JSON"):
        load_config(None, {})


@given(
    poses=st.lists(st.sampled_from(sorted(POSES)), min_size=6, max_size=8),
    verification=st.sampled_from(sorted(POSES)),
    separation=st.floats(1.0, 120.0),
)
def test_an_accepted_plan_lets_every_pose_be_taken_in_turn(
    poses: list[str], verification: str, separation: float
) -> None:
    """No pose twice, the verification unseen, every pose far enough from the others."""
    try:
        check_plan(tuple(poses), verification, separation, "six")
    except ValueError:
        return
    assert len(set(poses)) == len(poses)
    assert verification not in poses
    everything = [pose(name).gravity_body for name in (*poses, verification)]
    for i, a in enumerate(everything):
        for b in everything[:i]:
            assert angle_deg(a, b) >= separation


def test_the_default_plan_can_finish() -> None:
    check_plan(CALIBRATION_POSES, VERIFICATION_POSE, 30.0, "six")


# -- journals that cannot be resumed ---------------------------------------------------------


def _journal(**changes: object) -> str:
    journal = RunJournal(
        run_id=uuid4(),
        serial="PT000042",
        station_id="st-1",
        operator_id="op-7",
        started_at=datetime(2026, 11, 2, 8, tzinfo=UTC),
        poses=(*CALIBRATION_POSES, VERIFICATION_POSE),
    )
    return json.dumps({**json.loads(journal.model_dump_json()), **changes})


def _cut(text: str) -> bytes:
    """The journal as a power cut during a write without fsync could leave it."""
    return text[: text.index('"operator_id"') + 5].encode()


@pytest.mark.parametrize(
    ("content", "serial", "reason"),
    [
        (_cut(_journal()), "PT000042", "is cut short or not JSON"),
        (_journal().encode().replace(b"op-7", b"op-\xff"), "PT000042", "is not UTF-8 text"),
        (_journal(poses=["face_up", "toe_upp"]).encode(), "PT000042", "unknown pose 'toe_upp'"),
        (b"\x00\x01\x02", None, "is cut short or not JSON"),
        (b"", None, "is cut short or not JSON"),
    ],
    ids=["torn", "latin-1", "unknown pose", "binary", "empty"],
)
def test_an_unreadable_journal_is_kept_aside_and_named(
    tmp_path: Path, content: bytes, serial: str | None, reason: str
) -> None:
    path = tmp_path / "journal-st-1.json"
    path.write_bytes(content)
    discarded = JournalFile(path).load()
    assert isinstance(discarded, DiscardedJournal)
    assert discarded.serial == serial
    assert reason in discarded.reason
    assert not path.exists()
    assert discarded.kept_as.read_bytes() == content
    assert discarded.kept_as.name.startswith("journal-st-1.json.")
    assert discarded.kept_as.name.endswith(".unreadable")
    unit = f"unit {serial}" if serial else "a unit (serial unreadable)"
    assert discarded.sentence.startswith(f"the interrupted run of {unit} was discarded: ")
    assert JournalFile(path).load() is None


def test_the_operator_is_told_at_start_which_run_was_discarded(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    data = tmp_path / "data"
    data.mkdir()
    (data / "journal-st-1.json").write_bytes(_journal().encode().replace(b"op-7", b"op-\xff"))
    env = {
        "CALSTATION_DATA_DIR": str(data),
        "CALSTATION_DATABASE_URL": f"sqlite:///{tmp_path / 'r.sqlite3'}",
        "PATH": "/usr/bin:/bin",
    }
    result = run_cli("run", "--port", "/dev/null", "--station", "st-1", env=env, input="")
    assert result.returncode == 0, result.stderr
    assert (
        "the interrupted run of unit PT000042 was discarded: its journal is not UTF-8 text; "
        "kept as journal-st-1.json." in result.stdout
    )
    assert len(list(data.glob("journal-st-1.json.*.unreadable"))) == 1
