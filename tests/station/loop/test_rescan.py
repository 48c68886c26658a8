"""A unit scanned again after it passed: the station asks, and an abort changes nothing.

A real ``calstation run`` process in a pty, a virtual putter on its port, the embedded
SQLite results database.
"""

import json
import os
import sqlite3
from collections.abc import Iterator
from pathlib import Path

import pexpect
import pytest

from station.domain.sensors.faults import Faults
from tests.conftest import REPO_ROOT, CliRunner
from tests.station.loop.test_station_terminal import POSE_ASKED, Station
from tests.terminal import hang_guard

pytestmark = hang_guard


@pytest.fixture
def station(tmp_path: Path) -> Iterator[Station]:
    s = Station(tmp_path)
    yield s
    s.close()


def test_a_passed_unit_scanned_again_is_asked_about_and_an_abort_leaves_it_shipped(
    station: Station,
) -> None:
    child = station.start()
    station.scan()
    assert station.follow() == "PASS"
    child.expect("next: SHIP")
    child.expect("Scan the next unit's serial number")
    station.scan()
    child.expect(r"PT000042 passed at \d\d:\d\d on st-1: calibrate again\? y/n")
    child.send("n")
    child.expect("not calibrated again: scan the next unit")
    station.scan()
    child.expect("calibrate again\\? y/n")
    child.send("y")
    station.asked = None
    station.follow(until_pose=2)  # one pose taken: the abort is recorded
    child.send("a")
    child.expect("abort this unit\\? press y")
    child.send("y")
    child.expect("FAIL  unit PT000042")
    child.expect("next: SHIP")  # it holds the coefficients of its pass
    (answer,) = station.rows("select calibration from units")[0]
    unit = json.loads(str(answer))
    passed, aborted = station.rows("select run_id from runs order by started_at")
    assert unit["verdict"] == "pass"
    assert unit["holds"]["run_id"].replace("-", "") == str(passed[0]).replace("-", "")
    assert unit["latest"]["run_id"].replace("-", "") == str(aborted[0]).replace("-", "")
    assert unit["latest"]["disposition"] == "ship"


def test_a_unit_past_its_retest_limit_goes_to_rework(tmp_path: Path) -> None:
    limits = tmp_path / "limits.toml"
    shipped = (REPO_ROOT / "station" / "domain" / "profiles" / "limits.toml").read_text()
    # Every unit fails its sensitivity; one attempt is allowed.
    limits.write_text(
        shipped.replace("upper = 860.16", "upper = 790.0").replace(
            'version = "1"', 'version = "1"\nretest_limit = 1', 1
        )
    )
    limited = Station(tmp_path, limits=limits)
    try:
        child = limited.start()
        limited.scan()
        assert limited.follow() == "FAIL"
        child.expect("next: REWORK")
        child.expect("Scan the next unit's serial number")
        limited.scan()
        child.expect(r"PT000042 has failed 1 attempts \(limit 1\): send it to rework")
        assert limited.rows("select count(*) from runs") == [(1,)]
    finally:
        limited.close()


def test_a_unit_sent_to_rework_is_refused_until_a_review_releases_it(
    tmp_path: Path, run_cli: CliRunner
) -> None:
    broken = Station(tmp_path, faults=Faults(saturate_axis="y"))
    env = {**os.environ, "CALSTATION_DATABASE_URL": broken.database_url}
    review = ("review", "PT000042", "--by", "qe-ana", "--repair", "U3 reflowed")
    try:
        child = broken.start()
        broken.scan()
        assert broken.follow() == "FAIL"
        child.expect("next: REWORK")
        child.expect("Scan the next unit's serial number")
        broken.scan()
        child.expect(
            r"PT000042 was sent to rework at \d\d:\d\d \(saturated\): it is not calibrated "
            r"until a quality review releases it"
        )
        assert broken.rows("select count(*) from runs") == [(1,)]
        released = run_cli(
            *review, "--decision", "retest", "--root-cause", "cracked joint", env=env
        )
        assert released.returncode == 0, released.stderr
        # Repaired on its own cable: the unit streamed its rail counts into the port all
        # the while, and the new run starts from a flushed port and a fresh stream.
        broken.putter.faults.saturate_axis = None
        broken.asked = None
        broken.scan()
        # The new run asks for its first pose (the last verdict was on screen until then);
        # judged on the rail counts left in the port, it was stored at once, failed.
        while child.expect([POSE_ASKED, pexpect.TIMEOUT], timeout=0.2) == 1:
            with sqlite3.connect(broken.database) as db:
                (runs,) = db.execute("select count(*) from runs").fetchone()
            assert runs == 1, "the new run was judged before a pose was asked"
        assert broken.follow() == "PASS"
        child.expect("next: SHIP")
        again = run_cli(*review, "--decision", "scrap", "--root-cause", "too late", env=env)
        assert again.returncode == 2  # it passed: not on hold, nothing to review
        assert "is not on hold" in again.stderr
    finally:
        broken.close()


def test_a_scrapped_unit_is_refused_for_good(tmp_path: Path, run_cli: CliRunner) -> None:
    broken = Station(tmp_path, faults=Faults(saturate_axis="y"))
    env = {**os.environ, "CALSTATION_DATABASE_URL": broken.database_url}
    try:
        child = broken.start()
        broken.scan()
        assert broken.follow() == "FAIL"
        child.expect("Scan the next unit's serial number")
        scrapped = run_cli(
            "review", "PT000042", "--decision", "scrap", "--by", "qe-ana",
            "--root-cause", "housing cracked", "--repair", "none: not worth it", env=env,
        )  # fmt: skip
        assert scrapped.returncode == 0, scrapped.stderr
        broken.scan()
        child.expect(
            r"PT000042 was scrapped by qe-ana on \d\d:\d\d \(housing cracked\): it is not "
            "calibrated again"
        )
        assert broken.rows("select count(*) from runs") == [(1,)]
    finally:
        broken.close()
