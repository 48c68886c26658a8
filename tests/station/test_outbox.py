"""The outbox and the journal: nothing lost, nothing stored twice."""

from datetime import UTC, datetime
from pathlib import Path
from uuid import uuid4

from sqlalchemy import func, select

from db import Database
from db.models import Run
from station.journal import DiscardedJournal, JournalFile, RunJournal
from station.outbox import Outbox
from station.storage import DatabaseStore, HttpStore
from tests.db.records import make_record


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
