"""The outbox and the journal: nothing lost, nothing stored twice, nothing stops it."""

import itertools
import json
import os
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from uuid import UUID, uuid4

import httpx
import pytest
from hypothesis import given
from hypothesis import strategies as st
from rich.console import Console
from sqlalchemy import func, select

from db import Database
from db.models import Run, StationOutbox
from station.domain.record.outbox_report import OutboxReport
from station.domain.record.records import RunRecord
from station.loop.screens import header
from station.results.backoff import FIRST_S, RecordBackoff
from station.results.journal import DiscardedJournal, JournalFile, RunJournal
from station.results.outbox import Outbox
from station.results.outbox_files import UnreadableRecordError, read_record, reason_of
from station.results.storage import DatabaseStore, HttpStore, SubmitOutcome
from tests.conftest import CliRunner
from tests.db.records import make_record
from tests.station.results.test_storage import poison


def stored_runs(database: Database) -> int:
    with database.session() as session:
        return int(session.scalar(select(func.count()).select_from(Run)) or 0)


def test_every_run_is_stored_exactly_once_even_when_sent_again(
    tmp_path: Path, database: Database
) -> None:
    outbox = Outbox(tmp_path / "outbox")
    first, second = make_record(serial="PT-1"), make_record(serial="PT-2")
    outbox.put(first)
    outbox.put(second)
    assert outbox.count() == 2
    store = DatabaseStore(database=database)
    result = outbox.sync(store)
    assert (result.stored, result.pending, result.error) == (2, 0, None)
    # A crash between the store's answer and the removal: the record is sent again.
    outbox.put(first)
    assert outbox.sync(store).stored == 1
    assert stored_runs(database) == 2
    assert outbox.count() == 0


def test_an_unreachable_store_keeps_every_record(tmp_path: Path) -> None:
    outbox = Outbox(tmp_path / "outbox")
    outbox.put(make_record(serial="PT-1"))
    outbox.put(make_record(serial="PT-2"))
    with HttpStore("http://127.0.0.1:9", "no-key", timeout=0.5) as store:  # nothing listens on 9
        result = outbox.sync(store)
    assert result.stored == 0
    assert result.pending == 2
    assert result.error is not None
    assert "unreachable" in result.error


def test_a_refused_record_is_kept_aside_with_its_reason(tmp_path: Path, database: Database) -> None:
    outbox = Outbox(tmp_path / "outbox")
    record = make_record(serial="PT-1")
    store = DatabaseStore(database=database)
    outbox.put(record)
    outbox.sync(store)
    clash = record.model_copy(update={"serial": "PT-9"})  # same run id, other content
    outbox.put(clash)
    result = outbox.sync(store)
    assert (result.stored, result.refused) == (0, 1)
    kept = outbox.refused_dir / f"{record.run_id}.json"
    assert kept.exists()
    assert (outbox.refused_dir / f"{record.run_id}.reason.txt").read_text().strip()
    assert outbox.count() == 0


def test_journal_round_trip_and_an_unreadable_journal_is_kept_aside(tmp_path: Path) -> None:
    path = tmp_path / "journal.json"
    journal_file = JournalFile(path)
    assert journal_file.load() is None
    journal = RunJournal(
        run_id=uuid4(),
        serial="PT000001",
        station_id="st",
        operator_id="op",
        started_at=datetime.now(UTC),
        poses=("face_up", "face_down"),
    )
    journal_file.save(journal)
    loaded = journal_file.load()
    assert loaded is not None
    assert loaded.run_id == journal.run_id
    assert loaded.next_pose == 0
    path.write_text("{ torn")
    discarded = journal_file.load()
    assert isinstance(discarded, DiscardedJournal)
    assert discarded.kept_as.read_text() == "{ torn"
    assert journal_file.load() is None


GOOD = make_record(serial="PT-GOOD").model_dump_json().encode()

#: Unreadable outbox files, and a word their reason must hold.
UNREADABLE: dict[str, tuple[bytes, str]] = {
    "truncated": (GOOD[: len(GOOD) // 2], "not JSON"),
    "empty": (b"", "empty"),
    "binary": (bytes(range(256)), "not UTF-8"),
    "latin-1": (GOOD.replace(b'"PT-GOOD"', b'"PT-\xe9"'), "not UTF-8"),
    "not a run": (b'{"run_id": "x", "serial": "PT-3"}', "not a valid run record"),
}


def age(path: Path, seconds_ago: int) -> None:
    """Make ``path`` look written ``seconds_ago`` (the outbox sends oldest first)."""
    stamp = datetime.now(UTC).timestamp() - seconds_ago
    os.utime(path, (stamp, stamp))


@pytest.mark.parametrize("kind", UNREADABLE)
def test_an_unreadable_file_is_set_aside_and_the_runs_behind_it_are_stored(
    tmp_path: Path, database: Database, kind: str
) -> None:
    content, reason = UNREADABLE[kind]
    outbox = Outbox(tmp_path / "outbox")
    bad = outbox.directory / f"{uuid4()}.json"
    bad.write_bytes(content)
    age(bad, 60)  # at the head of the queue
    outbox.put(make_record(serial="PT-1"))
    outbox.put(make_record(serial="PT-2"))
    result = outbox.sync(DatabaseStore(database=database))
    assert (result.stored, result.unreadable, result.pending, result.error) == (2, 1, 0, None)
    assert stored_runs(database) == 2
    kept = outbox.unreadable_dir / bad.name
    assert kept.read_bytes() == content  # nothing lost
    said = reason_of(kept)
    assert said is not None
    assert reason in said
    assert outbox.set_aside() == (1, 0)
    assert result.note() == "1 unreadable set aside: see calstation outbox list"


@given(st.binary(max_size=300))
def test_any_bytes_are_a_run_record_or_one_line_saying_why_not(data: bytes) -> None:
    path = Path(f"/tmp/calstation-read-{os.getpid()}.json")
    path.write_bytes(data)
    try:
        read_record(path)
    except UnreadableRecordError as exc:
        reason = str(exc)
    else:
        reason = "read"
    finally:
        path.unlink()
    assert reason
    assert "\n" not in reason


@given(st.integers(min_value=0, max_value=len(GOOD) - 1))
def test_a_torn_record_is_unreadable_and_a_whole_one_reads_back(cut: int) -> None:
    path = Path(f"/tmp/calstation-torn-{os.getpid()}.json")
    path.write_bytes(GOOD[:cut])
    try:
        with pytest.raises(UnreadableRecordError):
            read_record(path)
        path.write_bytes(GOOD)
        assert read_record(path).serial == "PT-GOOD"
    finally:
        path.unlink()


class Counting:
    """A real store, counting what the outbox asked of it."""

    def __init__(self, store: DatabaseStore) -> None:
        self.store = store
        self.sent: list[str] = []

    def submit(self, record: RunRecord, outbox: OutboxReport | None = None) -> SubmitOutcome:
        self.sent.append(record.serial)
        return self.store.submit(record, outbox)

    def close(self) -> None:
        self.store.close()


def test_a_poison_run_on_postgresql_never_holds_up_the_runs_behind_it(
    tmp_path: Path, database: Database
) -> None:
    if database.is_sqlite:
        pytest.skip("SQLite stores 1e300 as it is")
    now = [0.0]
    outbox = Outbox(tmp_path / "outbox", backoff=RecordBackoff(lambda: now[0]))
    outbox.put(poison(make_record(serial="PT-POISON")))
    age(outbox.pending()[0], 60)
    outbox.put(make_record(serial="PT-1"))
    store = Counting(DatabaseStore(database=database))
    result = outbox.sync(store)
    assert (result.stored, result.error) == (1, None)
    if result.unreadable:  # the model's bounds refuse the record before the store sees it
        assert outbox.set_aside() == (1, 0)
        assert store.sent == ["PT-1"]
        return
    assert (result.failing, result.pending) == (1, 1)
    assert result.failure is not None
    assert "out of range" in result.failure
    assert store.sent == ["PT-POISON", "PT-1"]
    outbox.put(make_record(serial="PT-2"))
    assert outbox.sync(store).stored == 1
    assert store.sent[2:] == ["PT-2"]  # the poison waits its turn
    now[0] += FIRST_S
    assert outbox.sync(store).failing == 1
    assert store.sent[3:] == ["PT-POISON"]
    assert stored_runs(database) == 2


DAY_S = 86_400


class Reporting(Counting):
    """A real store, keeping the outbox report each run came with."""

    def __init__(self, store: DatabaseStore) -> None:
        super().__init__(store)
        self.reports: list[OutboxReport | None] = []

    def submit(self, record: RunRecord, outbox: OutboxReport | None = None) -> SubmitOutcome:
        self.reports.append(outbox)
        return super().submit(record, outbox)


def test_each_run_goes_with_what_waits_behind_it_and_the_store_keeps_the_latest(
    tmp_path: Path, database: Database
) -> None:
    outbox = Outbox(tmp_path / "outbox")
    # Days apart: the seconds the sync itself takes never blur which run is the oldest.
    for serial, days_ago in (("PT-1", 30), ("PT-2", 20), ("PT-3", 10)):
        outbox.put(make_record(serial=serial))
        age(outbox.pending()[-1], days_ago * DAY_S)
    outbox.refused_dir.mkdir()
    (outbox.refused_dir / "refused.json").write_text("{}")
    store = Reporting(DatabaseStore(database=database))
    assert outbox.sync(store).stored == 3
    assert store.sent == ["PT-1", "PT-2", "PT-3"]
    first, second, last = store.reports
    assert first is not None
    assert second is not None
    assert (first.queued, first.set_aside, first.oldest_s // DAY_S) == (2, 1, 20)
    assert (second.queued, second.set_aside, second.oldest_s // DAY_S) == (1, 1, 10)
    assert last == OutboxReport(queued=0, oldest_s=0, set_aside=1)
    with database.session() as session:
        (kept,) = session.scalars(select(StationOutbox)).all()
    assert (kept.station_id, kept.queued, kept.oldest_s, kept.set_aside) == (
        make_record().station_id,
        0,
        0,
        1,
    )


def echo_server(
    fails: set[UUID], tried: list[float], now: list[float]
) -> Callable[[httpx.Request], httpx.Response]:
    """A results server storing everything but failing (500) on the runs in ``fails``.

    ``tried`` gets the clock's reading at every request for a failing run.
    """

    def answer(request: httpx.Request) -> httpx.Response:
        body = json.loads(request.content)
        if UUID(body["run_id"]) in fails:
            tried.append(now[0])
            return httpx.Response(500, json={"detail": "internal error"})
        return httpx.Response(201, json={**body, "received_at": datetime.now(UTC).isoformat()})

    return answer


def test_a_failing_run_is_retried_with_growing_backoff_until_it_is_stored(
    tmp_path: Path,
) -> None:
    # The real server answers 500 to no valid record: a mock transport plays a broken one.
    now, tried = [0.0], list[float]()
    outbox = Outbox(tmp_path / "outbox", backoff=RecordBackoff(lambda: now[0]))
    stuck = make_record(serial="PT-STUCK")
    outbox.put(stuck)
    failing = {stuck.run_id}
    transport = httpx.MockTransport(echo_server(failing, tried, now))
    with HttpStore("http://results", "key", transport=transport) as store:
        first = outbox.sync(store)
        assert (first.failing, first.pending) == (1, 1)
        note = first.note()
        assert note is not None
        assert "500" in note
        assert "retried with backoff" in note
        while len(tried) < 4:
            now[0] += 1
            outbox.put(make_record(serial=f"PT-{now[0]:.0f}"))  # stored at once, every time
            assert outbox.sync(store).pending == 1
        assert [b - a for a, b in itertools.pairwise(tried)] == [
            FIRST_S,
            2 * FIRST_S,
            4 * FIRST_S,
        ]
        failing.clear()
        now[0] += 8 * FIRST_S
        assert outbox.sync(store).stored == 1
    assert outbox.count() == 0


def test_a_refused_key_keeps_every_run_queued_until_the_key_works(
    tmp_path: Path, live_url: str, database: Database, station_key: str
) -> None:
    outbox = Outbox(tmp_path / "outbox")
    for serial in ("PT-1", "PT-2", "PT-3"):
        outbox.put(make_record(serial=serial))
    with HttpStore(live_url, "csk_revoked") as store:
        result = outbox.sync(store)
    assert (result.stored, result.refused, result.pending) == (0, 0, 3)
    note = result.note()
    assert note is not None
    assert note.startswith(
        "3 runs wait in the outbox: results server refused this station's API key (401"
    )
    assert note.endswith("fix api_key")
    assert outbox.set_aside() == (0, 0)
    with HttpStore(live_url, station_key) as store:
        assert outbox.sync(store).stored == 3
    assert stored_runs(database) == 3


def test_the_top_line_counts_what_was_set_aside_beside_the_backlog() -> None:
    console = Console(width=200, record=True)
    console.print(header("st-1", "op-7", "v0", 2, (1, 3)))
    top = console.export_text().splitlines()[0]
    assert top.endswith("outbox 2 · 1 unreadable · 3 refused (calstation outbox list)")
    console.print(header("st-1", "op-7", "v0", 0))
    assert console.export_text().splitlines()[0].endswith("outbox empty")


def test_a_poison_run_the_server_fails_on_never_holds_up_the_runs_behind_it(
    tmp_path: Path, live_url: str, database: Database, station_key: str
) -> None:
    outbox = Outbox(tmp_path / "outbox")
    outbox.put(poison(make_record(serial="PT-POISON")))
    age(outbox.pending()[0], 60)
    outbox.put(make_record(serial="PT-1"))
    with HttpStore(live_url, station_key) as store:
        result = outbox.sync(store)
    assert result.error is None
    with database.session() as session:
        assert session.scalar(select(func.count()).where(Run.serial == "PT-1")) == 1
    # Whichever comes first: the server fails on it (500 on PostgreSQL: backoff), stores it
    # (SQLite takes 1e300), refuses it (422), or the station's own model does (unreadable).
    if result.stored == 2:
        assert database.is_sqlite
    else:
        assert result.failing + result.refused + result.unreadable == 1


def _not_a_file(kind: str, path: Path, elsewhere: Path) -> None:
    """Make ``path`` a FIFO, a directory or a symbolic link to a valid record."""
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "directory":
        path.mkdir()
        (path / "inside.json").write_bytes(GOOD)
    else:
        elsewhere.write_bytes(GOOD)
        path.symlink_to(elsewhere)


@pytest.mark.timeout(60)
@pytest.mark.parametrize(
    ("kind", "reason"),
    [("fifo", "a FIFO"), ("directory", "a directory"), ("symlink", "a symbolic link")],
)
def test_a_path_that_is_no_file_is_set_aside_unopened_and_the_runs_behind_it_are_stored(
    tmp_path: Path, database: Database, run_cli: CliRunner, kind: str, reason: str
) -> None:
    """A FIFO named like a record would block a reader with no writer forever: ``outbox
    list`` goes by it without opening it and sets it aside, with its reason, as the
    sender would."""
    outbox = Outbox(tmp_path / "data" / "outbox")
    odd = outbox.directory / f"{uuid4()}.json"
    _not_a_file(kind, odd, tmp_path / "elsewhere.json")
    outbox.put(make_record(serial="PT-1"))
    env = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    env["CALSTATION_DATA_DIR"] = str(tmp_path / "data")
    listed = run_cli("outbox", "list", env=env, timeout=30)
    assert listed.returncode == 0, listed.stderr
    line = next(line for line in listed.stdout.splitlines() if odd.stem[:8] in line)
    assert line.startswith("unreadable  ")
    assert line.endswith(f"not a record file: {reason}")
    result = outbox.sync(DatabaseStore(database=database))
    assert (result.stored, result.unreadable, result.pending) == (1, 0, 0)
    kept = outbox.unreadable_dir / odd.name
    assert os.path.lexists(kept)  # nothing removed: set aside as it was
    assert reason_of(kept) == f"not a record file: {reason}"
    shown = run_cli("outbox", "show", odd.stem, env=env, timeout=30)
    assert shown.returncode == 0, shown.stderr
    assert f"(not a record file: {reason})" in shown.stdout
