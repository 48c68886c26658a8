"""``calstation run`` refuses, at start and in one line, what would fail it later.

Every case is a real ``calstation`` process. A read-only or full data directory is a
real tmpfs, mounted in a user and mount namespace of the station's own
(``unshare``), so the test needs no privilege; it is skipped where the kernel does
not allow that.
"""

import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

import pexpect
import pytest

from station.simulator.putter import VirtualPutter
from tests.conftest import REPO_ROOT, CliRunner
from tests.terminal import hang_guard, spawn, wait_until

SERIAL = "PT000042"


def _env(tmp_path: Path, **variables: str) -> dict[str, str]:
    clean = {k: v for k, v in os.environ.items() if not k.startswith("CALSTATION_")}
    return {
        **clean,
        "CALSTATION_DATA_DIR": str(tmp_path / "data"),
        "CALSTATION_DATABASE_URL": f"sqlite:///{tmp_path / 'results.sqlite3'}",
        **variables,
    }


def _one_line_error(result: subprocess.CompletedProcess[str], *parts: str) -> None:
    assert result.returncode == 2, result.stderr
    assert result.stderr.count("\n") == 1, result.stderr
    assert result.stderr.startswith("calstation: error: ")
    for part in parts:
        assert part in result.stderr


@pytest.fixture
def putter(tmp_path: Path) -> Iterator[Path]:
    with VirtualPutter(seed=5, serial=SERIAL, speed=20.0) as unit:
        unit.serve_pty(tmp_path / "putter")
        yield tmp_path / "putter"


@pytest.mark.parametrize(
    ("arguments", "variables", "message"),
    [
        ((), {}, "no putter port: give --port"),
        (("--port", "/dev/null"), {"CALSTATION_DATA_DIR": "{tmp}/file"}, "is a file, not a dir"),
        (("--port", "/dev/null"), {"CALSTATION_RUN": "{poses"}, "CALSTATION_RUN: not valid JSON"),
        (
            ("--port", "/dev/null"),
            {"CALSTATION_DATABASE_URL": "postgress://db/calstation"},
            "database_url: unknown scheme 'postgress'",
        ),
    ],
)
def test_a_station_that_could_not_work_stops_at_start(
    run_cli: CliRunner,
    tmp_path: Path,
    arguments: tuple[str, ...],
    variables: dict[str, str],
    message: str,
) -> None:
    (tmp_path / "file").write_text("not a directory\n")
    variables = {k: v.replace("{tmp}", str(tmp_path)) for k, v in variables.items()}
    result = run_cli("run", *arguments, env=_env(tmp_path, **variables), input="")
    _one_line_error(result, message)
    assert not (tmp_path / "data" / "outbox").exists()


def test_a_pose_plan_that_could_never_finish_a_unit_stops_at_start(
    run_cli: CliRunner, tmp_path: Path
) -> None:
    config = tmp_path / "station.toml"
    poses = '["face_up", "face_up", "toe_up", "toe_down", "shaft_up", "shaft_down"]'
    config.write_text(f"[run]\nposes = {poses}\n")
    result = run_cli("run", "--config", str(config), "--port", "/dev/null", env=_env(tmp_path))
    _one_line_error(result, str(config), "run: poses: 'face_up' is listed twice")


# -- the data directory on a real read-only or full file system ---------------------------

UNSHARE = shutil.which("unshare")


def _namespaces_work(tmp_path: Path) -> bool:
    if UNSHARE is None:
        return False
    probe = subprocess.run(
        [
            UNSHARE,
            "--user",
            "--map-root-user",
            "--mount",
            "mount",
            "-t",
            "tmpfs",
            "t",
            str(tmp_path),
        ],
        capture_output=True,
        check=False,
    )
    return probe.returncode == 0


@pytest.fixture
def mountable(tmp_path: Path) -> None:
    if not _namespaces_work(tmp_path):
        pytest.skip("no user and mount namespaces here (unshare) for a real small file system")


def _in_tmpfs(mount: Path, options: str, *command: str) -> list[str]:
    """``command`` run with a fresh tmpfs (``options``) on ``mount``, in its own namespace."""
    assert UNSHARE is not None
    script = f'mount -t tmpfs -o {options} calstation-test "$0" && exec "$@"'
    return [
        UNSHARE,
        "--user",
        "--map-root-user",
        "--mount",
        "sh",
        "-c",
        script,
        str(mount),
        *command,
    ]


@pytest.mark.usefixtures("mountable")
@pytest.mark.parametrize(
    ("options", "message"),
    [("ro", "the file system is read-only"), ("size=32k", "the disk is full")],
)
def test_a_read_only_or_full_data_directory_stops_at_start(
    tmp_path: Path, putter: Path, options: str, message: str
) -> None:
    data = tmp_path / "data"
    data.mkdir()
    command = [sys.executable, "-m", "station", "run", "--port", str(putter)]
    result = subprocess.run(
        _in_tmpfs(data, options, *command),
        env={**_env(tmp_path), "PYTHONPATH": str(REPO_ROOT)},
        capture_output=True,
        text=True,
        input="",
        timeout=120,
        check=False,
    )
    _one_line_error(result, f"data directory {data}: {message}")


def _write_forever(handle: BinaryIO) -> None:
    while True:
        handle.write(b"\0" * 4096)


def _fill(path: Path) -> None:
    """Write ``path`` until its file system is full."""
    with path.open("wb", buffering=0) as handle, pytest.raises(OSError, match="No space left"):
        _write_forever(handle)


@hang_guard
@pytest.mark.usefixtures("mountable")
def test_a_disk_full_at_the_scan_is_said_and_the_unit_goes_on_in_memory(
    tmp_path: Path, putter: Path
) -> None:
    data = tmp_path / "data"
    data.mkdir()
    command = [sys.executable, "-m", "station", "run", "--port", str(putter)]
    argv = _in_tmpfs(data, "size=256k", *command)
    child = spawn(
        argv,
        env={**_env(tmp_path), "PYTHONPATH": str(REPO_ROOT), "TERM": "xterm-256color"},
        cwd=REPO_ROOT,
    )
    try:
        child.expect("Scan the next unit's serial number")
        # The station's view of its data directory, from outside its namespace.
        filler = Path(f"/proc/{child.pid}/root") / str(data).lstrip("/") / "filler"
        _fill(filler)
        child.send(SERIAL + "\r")
        # The unit starts (its screen asks for pose 1), the disk's line stands above it.
        child.expect("disk full — the unit is kept in memory")
        child.expect(r"pose \d of 7")
        journal = filler.with_name("journal-station-1.json")
        assert not journal.exists()
        filler.unlink()
        # Once there is room the owed journal is written (DiskWatch retries every second);
        # the screen is read meanwhile so that the station never blocks on its terminal.
        wait_until(
            journal.exists,
            "the owed journal",
            tick=lambda: child.expect([pexpect.TIMEOUT], timeout=0.1),
        )
    finally:
        child.sendeof()
        child.expect(pexpect.EOF)
