"""A data directory that refuses writes mid-unit: nothing lost, the station goes on.

The faults are real: a tiny tmpfs mounted for the test and filled to the last byte
(ENOSPC), or remounted read-only (EROFS, which stops root too). Mounting needs root
(CAP_SYS_ADMIN); elsewhere these tests skip.
"""

import errno
import subprocess
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path
from typing import BinaryIO
from uuid import uuid4

import pexpect
import pytest

from station.domain.record.records import RunRecord
from station.results.disk import DiskWatch
from station.results.journal import JournalFile, RunJournal
from station.results.outbox import Outbox
from station.results.storage import DatabaseStore, HttpStore
from tests.db.records import make_record
from tests.servers import free_port
from tests.station.loop.test_station_terminal import Station
from tests.terminal import hang_guard, wait_until


class SmallDisk:
    """A 256 KiB tmpfs at ``path`` that the test fills, frees, or makes read-only."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.filler = path / "filler"

    def fill(self) -> None:
        """Take every free byte: the next write of anything fails with ENOSPC."""
        with self.filler.open("ab", buffering=0) as handle:
            for size in (65536, 1):
                with pytest.raises(OSError, match="No space left") as full:
                    _write_forever(handle, b"\0" * size)
                assert full.value.errno == errno.ENOSPC

    def free(self) -> None:
        self.filler.unlink()

    def read_only(self, flag: bool) -> None:
        mode = "ro" if flag else "rw"
        subprocess.run(["mount", "-o", f"remount,{mode}", str(self.path)], check=True)


def _write_forever(handle: BinaryIO, chunk: bytes) -> None:
    while True:
        handle.write(chunk)


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[SmallDisk]:
    path = tmp_path / "data"
    path.mkdir()
    mounted = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    if mounted.returncode != 0:
        pytest.skip(f"cannot mount a small tmpfs here: {mounted.stderr.strip()}")
    try:
        yield SmallDisk(path)
    finally:
        subprocess.run(["umount", "-l", str(path)], check=True)


def journal() -> RunJournal:
    return RunJournal(
        run_id=uuid4(),
        serial="PT000001",
        station_id="st",
        operator_id="op",
        started_at=datetime.now(UTC),
        poses=("face_up", "face_down"),
    )


def test_a_full_disk_keeps_the_unit_in_memory_and_writes_it_when_space_returns(
    small_disk: SmallDisk,
) -> None:
    journal_file = JournalFile(small_disk.path / "journal.json")
    outbox = Outbox(small_disk.path / "outbox")
    now = [0.0]
    watch = DiskWatch(small_disk.path, [journal_file], outbox, clock=lambda: now[0])
    state = journal()
    small_disk.fill()
    journal_file.save(state)  # the pose's save: refused, owed
    assert not journal_file.path.exists()
    assert watch.check() == (
        f"disk full — the unit is kept in memory; free space in {small_disk.path} to continue"
    )
    record = make_record(serial="PT000001")
    outbox.put(record)  # the verdict: refused, kept in memory
    assert outbox.count() == 1
    now[0] += 1
    note = watch.check()
    assert note is not None
    assert "the unit and 1 finished run are kept in memory" in note
    small_disk.free()
    assert watch.check() is not None  # retried at most once a second
    now[0] += 1
    assert watch.check() is None
    assert JournalFile(journal_file.path).load() == state
    assert outbox.pending() == [outbox.directory / f"{record.run_id}.json"]
    assert outbox.unwritten == []


def test_a_run_the_disk_refused_is_sent_from_memory(small_disk: SmallDisk, tmp_path: Path) -> None:
    outbox = Outbox(small_disk.path / "outbox")
    small_disk.fill()
    outbox.put(make_record(serial="PT000001"))
    with HttpStore("http://127.0.0.1:9", "key", timeout=0.5) as down:  # nothing listens on 9
        assert outbox.sync(down).pending == 1  # still kept, in memory
    with DatabaseStore(f"sqlite:///{tmp_path / 'results.sqlite3'}") as store:
        result = outbox.sync(store)
    assert (result.stored, result.pending) == (1, 0)
    assert outbox.write_error is None
    assert not list(outbox.directory.glob("*.json"))


def test_a_read_only_data_dir_is_said_and_the_end_of_the_unit_is_done_later(
    small_disk: SmallDisk,
) -> None:
    journal_file = JournalFile(small_disk.path / "journal.json")
    outbox = Outbox(small_disk.path / "outbox")
    now = [0.0]
    watch = DiskWatch(small_disk.path, [journal_file], outbox, clock=lambda: now[0])
    journal_file.save(journal())
    small_disk.read_only(True)
    outbox.put(make_record(serial="PT000001"))
    journal_file.clear()  # the unit ended: its journal cannot go yet
    assert journal_file.path.exists()
    note = watch.check()
    assert note is not None
    assert note == (
        "read-only file system — the unit and 1 finished run are kept in memory; "
        f"make it writable in {small_disk.path} to continue"
    )
    small_disk.read_only(False)
    now[0] += 1
    assert watch.check() is None
    assert not journal_file.path.exists()
    assert outbox.count() == 1


@hang_guard
def test_a_full_disk_mid_unit_is_told_and_the_station_goes_on(
    small_disk: SmallDisk, tmp_path: Path
) -> None:
    station = Station(tmp_path)  # data dir: the small disk; results database: elsewhere
    try:
        child = station.start()
        station.scan()
        third = station.follow(until_pose=3)  # poses 1-2 taken and journaled
        small_disk.fill()
        station.asked = third
        station.putter.move_to(third, 1.0)
        child.expect("disk full — the unit is kept in memory")
        fifth = station.follow(until_pose=5)  # poses 3-4 taken in memory only
        saved = JournalFile(small_disk.path / "journal-st-1.json")
        loaded = saved.load()
        assert loaded is not None
        assert sorted(loaded.captures) == [0, 1]
        small_disk.free()
        journaled = [loaded]

        def four_poses_journaled() -> bool:
            journaled[0] = saved.load() or journaled[0]
            return len(journaled[0].captures) >= 4

        wait_until(four_poses_journaled, "the journal of poses 1-4", tick=station.tick)
        assert sorted(journaled[0].captures) == [0, 1, 2, 3]  # written once space returned
        small_disk.fill()  # full again at the verdict: the run is sent from memory
        station.asked = fifth
        station.putter.move_to(fifth, 1.0)
        assert station.follow() == "PASS"
        child.expect("Scan the next unit's serial number")
        station.wait_stored(1)
        assert station.rows("select serial, verdict from runs") == [("PT000042", "pass")]
        assert not saved.path.exists()  # the unit is done: nothing to resume
    finally:
        station.close()


@hang_guard
def test_stopping_with_a_run_only_in_memory_asks_then_saves_it_elsewhere(
    small_disk: SmallDisk, tmp_path: Path
) -> None:
    """The data directory turns read-only and the results server is gone: the finished
    run exists only in the station's memory. Ctrl-D does not stop the station but says
    so; a second Ctrl-D stops it, saving the run beside the data directory, exit 2."""
    station = Station(tmp_path)
    nobody = f"http://127.0.0.1:{free_port()}"
    try:
        child = station.start(extra=("--server", nobody, "--api-key", "csk_none"))
        station.scan()
        station.follow(until_pose=2)
        small_disk.read_only(True)
        assert station.follow() == "PASS"
        child.expect("Scan the next unit's serial number")
        child.sendcontrol("d")
        child.expect("NOT STOPPED: 1 finished run only in memory")
        assert child.isalive()
        child.sendcontrol("d")
        child.expect("stopped holding 1 run only in memory: saved to ")
        child.expect(pexpect.EOF)
        child.close()
        assert child.exitstatus == 2
    finally:
        small_disk.read_only(False)
        station.close()
    (saved,) = (tmp_path / "data-rescue").glob("*.json")
    record = RunRecord.model_validate_json(saved.read_text(encoding="utf-8"))
    assert (record.serial, record.verdict) == ("PT000042", "pass")


@hang_guard
def test_a_journal_left_by_a_read_only_disk_never_calibrates_a_stored_run_again(
    small_disk: SmallDisk, tmp_path: Path
) -> None:
    """The unit's run is stored, but the read-only disk kept its journal: at the next
    start the station offers to resume it, and "y" finds its run stored and discards it."""
    station = Station(tmp_path)
    try:
        child = station.start()
        station.scan()
        station.follow(until_pose=2)
        small_disk.read_only(True)
        assert station.follow() == "PASS"
        station.wait_stored(1)
        child.sendcontrol("d")
        child.expect(pexpect.EOF)
        small_disk.read_only(False)
        assert list(small_disk.path.glob("journal-*.json"))  # its removal was refused
        child = station.start(prompt=False)
        child.expect(r"Resume it\? press y")
        child.send("y")
        child.expect(r"is stored already: its journal was left behind, discarded")
        assert station.rows("select count(*) from runs") == [(1,)]
        assert not list(small_disk.path.glob("journal-*.json"))
    finally:
        station.close()
