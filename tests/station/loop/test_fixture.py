"""The multi-slot fixture, in-process over real ptys at high virtual speed.

Each slot's unit is a virtual putter on its own pty; a scripted operator scans the
slots, turns the whole fixture (each unit with its own mounting misalignment) and, in
some tests, pulls a cable. The station is :class:`station.loop.fixture.app.FixtureApp` with
its real journal files, outbox and SQLite database.
"""

import io
import sqlite3
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st
from rich.console import Console

from station.domain.product.limits import load_profile
from station.domain.quality.golden import GoldenUnit
from station.domain.sensors.faults import Faults
from station.domain.signals.poses import pose
from station.loop.config import StationConfig
from station.loop.fixture.app import FixtureApp, Stage
from station.loop.fixture.demo import mounts
from station.loop.fixture.plan import next_fixture_pose
from station.loop.keyboard import PolledKeys
from station.loop.slot import SlotState
from station.results.storage import DatabaseStore
from station.run.phases import Phase
from station.simulator.putter import VirtualPutter

SPEED = 10.0


class Fixture(PolledKeys):
    """Virtual putters in the slots' ptys and an operator who types and turns."""

    def __init__(self, tmp: Path, slots: int, seed: int = 3) -> None:
        self.tmp = tmp
        self.ports = [tmp / f"slot{n}" for n in range(1, slots + 1)]
        self.mounts = mounts(slots, seed)
        self.putters: dict[int, VirtualPutter] = {}
        self.keys: list[str] = []
        self.turned_to: int | None = None
        self.cycled = False
        self.app: FixtureApp | None = None
        self.on_tick: Callable[[FixtureApp], None] = lambda app: None
        self.log = io.StringIO()

    def plug(self, slot: int, serial: str, seed: int, faults: Faults | None = None) -> None:
        putter = VirtualPutter(seed=seed, serial=serial, speed=SPEED, faults=faults)
        putter.serve_pty(self.ports[slot - 1])
        putter.move_to(pose("face_up").rotation * self.mounts[slot - 1], 0.3)
        self.putters[slot] = putter

    def station(self, units: int | None = None, **settings: Any) -> FixtureApp:
        data = self.tmp / "data"
        config = StationConfig(
            station_id="fx",
            data_dir=data,
            slots=tuple(map(str, self.ports)),
            database_url=f"sqlite:///{data}/results.sqlite3",
            **settings,
        )
        console = Console(file=self.log, width=1000)
        self.app = FixtureApp(
            config=config,
            profile=load_profile(),
            open_store=lambda: DatabaseStore(config.database_url),
            keys=self,
            console=console,
            units=units,
            tick_s=0.005,
        )
        return self.app

    def read(self) -> str:
        """The station's key source: the keys queued, and the fixture turned as asked."""
        app = self.app
        assert app is not None
        self.on_tick(app)
        target = app.fixture_pose
        if app.stage is Stage.CYCLE and target is not None and target != self.turned_to:
            self.turned_to = target
            for slot, putter in self.putters.items():
                putter.move_to(app.poses[target].rotation * self.mounts[slot - 1], 1.0)
        self.cycled = self.cycled or app.stage is Stage.CYCLE
        if self.keys:
            return self.keys.pop(0)
        if app.stage is Stage.SCAN and self.cycled and app.scanner.looking is None:
            raise EOFError  # the cycle ended: stop
        return ""

    def serve(self, app: FixtureApp, timeout: float = 100.0) -> None:
        """Run the station until its keys end, within ``timeout`` wall seconds."""
        deadline = time.monotonic() + timeout
        previous = self.on_tick

        def guarded(a: FixtureApp) -> None:
            assert time.monotonic() < deadline, self.log.getvalue()[-3000:]
            previous(a)

        self.on_tick = guarded
        app.serve()
        self.on_tick = previous

    def close(self) -> None:
        for putter in self.putters.values():
            putter.close()


@pytest.fixture
def make_fixture(tmp_path: Path) -> Iterator[Callable[[int], Fixture]]:
    made: list[Fixture] = []

    def make(slots: int) -> Fixture:
        made.append(Fixture(tmp_path, slots))
        return made[-1]

    yield make
    for fixture in made:
        fixture.close()


def stored(fixture: Fixture) -> dict[str, tuple[str, str | None]]:
    with sqlite3.connect(fixture.tmp / "data" / "results.sqlite3") as db:
        rows = db.execute("select serial, verdict, disposition from runs").fetchall()
    return {serial: (verdict, disposition) for serial, verdict, disposition in rows}


def stored_slots(fixture: Fixture) -> dict[str, int | None]:
    with sqlite3.connect(fixture.tmp / "data" / "results.sqlite3") as db:
        return dict(db.execute("select serial, fixture_slot from runs").fetchall())


@pytest.mark.timeout(90)
def test_a_pulled_cable_and_a_saturated_unit_never_hold_up_the_unit_that_passes(
    make_fixture: Callable[[int], Fixture],
) -> None:
    fixture = make_fixture(3)
    fixture.plug(1, "PT000101", seed=101)
    fixture.plug(2, "PT000102", seed=102, faults=Faults(saturate_axis="y"))
    fixture.plug(3, "PT000103", seed=103)
    app = fixture.station()
    fixture.keys = list("PT000101\rPT000102\rPT000103\r")
    seen: dict[str, object] = {}

    def operator(app: FixtureApp) -> None:
        one, three = app.slots[0], app.slots[2]
        run = one.run
        if "pulled" not in seen and run is not None and len(run.journal.captures) >= 3:
            seen["pulled"] = len(run.journal.captures)
            fixture.putters[1].unplug()
        if "stored" not in seen and three.state is SlotState.DONE:
            # The third unit is done while the first still waits for its cable.
            seen["stored"] = three.record
            seen["first then"] = one.run.phase if one.run is not None else None
            seen["screen"] = render(app)
            fixture.putters[1].replug()

    fixture.on_tick = operator
    fixture.serve(app)

    assert seen["first then"] is Phase.RECONNECT
    record = seen["stored"]
    assert record is not None
    assert [(r.serial, r.verdict, r.disposition) for r in app.records][-1][0] == "PT000101"
    assert stored(fixture) == {
        "PT000101": ("pass", "ship"),
        "PT000102": ("fail", "rework"),
        "PT000103": ("pass", "ship"),
    }
    by_serial = {r.serial: r for r in app.records}
    assert [(f.code, f.axis) for f in by_serial["PT000102"].failures] == [("saturated", "y")]
    assert len(by_serial["PT000101"].poses) == 7  # its poses kept across the pulled cable
    screen = str(seen["screen"])
    assert "FAIL (saturated) → rework bin" in screen
    assert "PASS → good units" in screen
    assert "CABLE PULLED" in screen
    log = fixture.log.getvalue()
    assert "slot 2 → rework bin: PT000102: FAIL (saturated): rework" in log
    assert "cycle done: slot 1 → good units · slot 2 → rework bin · slot 3 → good units" in log
    assert "Traceback" not in log
    # Each slot's journal is gone once its unit is stored.
    assert not list((fixture.tmp / "data").glob("journal-*"))


def render(app: FixtureApp) -> str:
    # Wide enough that no row's state wraps (at 80 columns it may, by the other rows).
    console = Console(file=io.StringIO(), width=200, record=True)
    console.print(app.screen())
    return console.export_text()


@pytest.mark.timeout(60)
def test_bad_scans_are_one_line_each_and_the_other_slots_go_on(
    make_fixture: Callable[[int], Fixture],
) -> None:
    fixture = make_fixture(4)
    # Slot 1 holds PT000202, slot 2 holds PT000201; slot 3 has no port; slot 4 is empty.
    fixture.plug(1, "PT000202", seed=202)
    fixture.plug(2, "PT000201", seed=201)
    app = fixture.station()
    fixture.keys = [*"PT000201\r", "\r", *"PT000201\r", *"PT000201\r", *"PT000203\r", "\r"]
    screens: list[str] = []

    def look(app: FixtureApp) -> None:
        if app.stage is Stage.CYCLE and not screens:
            screens.append(render(app))
            for slot in app.running:
                assert slot.run is not None
                slot.run.abort()  # the scan is what is tested here

    fixture.on_tick = look
    fixture.serve(app)

    log = fixture.log.getvalue()
    lines = log.splitlines()
    assert any(
        line.startswith(f"slot 3: port {fixture.ports[2]}: no such device") for line in lines
    )
    assert (
        "wrong unit in slot 1: it reports PT000202, the label says PT000201: put PT000201 in "
        "slot 1 and scan again (Enter: leave slot 1 empty)"
    ) in lines
    assert "slot 1 left empty: skipped this cycle" in lines
    assert (
        "PT000201 is in slot 2 already: scan the unit in slot 3 (Enter: leave slot 3 empty)"
    ) in lines
    assert any(
        line.startswith("slot 3: cannot reach unit PT000203 on")
        and line.endswith("no such port: is the unit's cable plugged in?: skipped this cycle")
        for line in lines
    )
    assert "slot 4 left empty: skipped this cycle" in lines
    assert "fixture loaded (slots 2): turn it through the poses as asked" in lines
    assert "Traceback" not in log
    assert "slot 1 left empty" in screens[0]


@pytest.mark.timeout(90)
def test_each_slot_resumes_at_its_own_pose_after_a_restart(
    make_fixture: Callable[[int], Fixture],
) -> None:
    fixture = make_fixture(2)
    fixture.plug(1, "PT000301", seed=301)
    fixture.plug(2, "PT000302", seed=302)
    first = fixture.station()
    fixture.keys = list("PT000301\rPT000302\r")
    taken: dict[int, int] = {}

    def crash_after_three(app: FixtureApp) -> None:
        runs = [s.run for s in app.slots]
        if all(r is not None and len(r.journal.captures) >= 3 for r in runs):
            taken.update({i: len(r.journal.captures) for i, r in enumerate(runs) if r})
            raise EOFError  # the station stops with both units mid-run

    fixture.on_tick = crash_after_three
    fixture.serve(first)
    assert sorted(p.name for p in (fixture.tmp / "data").glob("journal-*")) == [
        "journal-fx-slot1.json",
        "journal-fx-slot2.json",
    ]

    fixture.on_tick = lambda app: None
    fixture.turned_to = None
    fixture.cycled = False
    second = fixture.station()
    fixture.keys = ["y"]
    fixture.serve(second)

    log = fixture.log.getvalue()
    assert (
        f"interrupted: slot 1 PT000301 at pose {taken[0] + 1} of 7, "
        f"slot 2 PT000302 at pose {taken[1] + 1} of 7: resume them? (y/n)"
    ) in log
    assert sorted((r.serial, r.verdict) for r in second.records) == [
        ("PT000301", "pass"),
        ("PT000302", "pass"),
    ]
    for record in second.records:
        assert [p.index for p in record.poses] == list(range(7))
    assert stored(fixture) == {"PT000301": ("pass", "ship"), "PT000302": ("pass", "ship")}
    # Each run records its slot, kept in the slot's journal across the restart.
    assert {r.serial: r.fixture_slot for r in second.records} == {"PT000301": 1, "PT000302": 2}
    assert stored_slots(fixture) == {"PT000301": 1, "PT000302": 2}


def test_a_fixture_waiting_for_its_golden_unit_starts_no_slot(
    make_fixture: Callable[[int], Fixture],
) -> None:
    fixture = make_fixture(2)
    fixture.plug(1, "PT000401", seed=401)
    golden = GoldenUnit(
        serial="PT900001",
        offset_counts=(2048.0, 2048.0, 2048.0),
        sensitivity_counts_per_g=(819.2, 819.2, 819.2),
    )
    app = fixture.station(golden=golden)
    fixture.keys = [*"PT000401\r", "\x00"]

    def stop_once_typed(app: FixtureApp) -> None:
        if fixture.keys == ["\x00"]:
            raise EOFError

    fixture.on_tick = stop_once_typed
    fixture.serve(app)
    log = fixture.log.getvalue()
    assert "GOLDEN UNIT due: scan golden unit PT900001 before the next unit" in log
    assert app.scanner.current is app.slots[0]  # still asking for slot 1
    assert not app.running
    assert "GOLDEN UNIT due" in render(app)


@given(
    needs=st.lists(st.integers(min_value=0, max_value=6), max_size=8),
    current=st.none() | st.integers(min_value=0, max_value=6),
)
def test_the_fixture_goes_forward_and_turns_back_only_when_nothing_is_ahead(
    needs: list[int], current: int | None
) -> None:
    target = next_fixture_pose(needs, current)
    if not needs:
        assert target is None
        return
    assert target in needs
    start = -1 if current is None else current
    if any(n >= start for n in needs):  # forward, to the nearest pose a slot needs
        assert target >= start
        assert not any(start <= n < target for n in needs)
    else:  # nothing ahead: back to the earliest pose still needed
        assert target == min(needs)


@pytest.mark.timeout(90)
def test_the_fixture_stays_in_its_first_pose_until_every_slot_is_loaded(
    make_fixture: Callable[[int], Fixture],
) -> None:
    fixture = make_fixture(2)
    fixture.plug(1, "PT000301", seed=301)
    fixture.plug(2, "PT000302", seed=302)
    app = fixture.station(units=2)
    fixture.keys = [*"PT000301\r"]
    held: list[int | None] = []

    def scan_slowly(app: FixtureApp) -> None:
        # The operator scans slot 2 only after slot 1's unit has taken the first pose.
        first = app.slots[0].run
        if app.stage is Stage.SCAN and first is not None and first.journal.captures and not held:
            held.append(app.fixture_pose)
            fixture.keys.extend("PT000302\r")

    fixture.on_tick = scan_slowly
    fixture.serve(app)

    lines = fixture.log.getvalue().splitlines()
    assert held == [0]
    loaded = lines.index("fixture loaded (slots 1, 2): turn it through the poses as asked")
    turns = [i for i, line in enumerate(lines) if line.startswith("fixture: pose ")]
    assert [lines[i].split(":")[1] for i in turns][:2] == [" pose 1 of 7", " pose 2 of 7"]
    assert turns[1] > loaded  # not turned on while slot 2 was loaded
    assert sum(lines[i].split(":")[1] == " pose 1 of 7" for i in turns) == 1  # never back
    assert {v for v, _ in stored(fixture).values()} == {"pass"}


@pytest.mark.timeout(90)
def test_labels_scanned_during_a_cycle_fill_the_next_and_a_unit_in_the_wrong_slot_is_caught(
    make_fixture: Callable[[int], Fixture],
) -> None:
    fixture = make_fixture(2)
    fixture.plug(1, "PT000501", seed=501)
    fixture.plug(2, "PT000502", seed=502)
    app = fixture.station()
    fixture.keys = list("PT000501\rPT000502\r")
    ahead = ["PT000601", "PT000501", "nope", "PT000601", "PT000602", "PT000603"]
    seen: dict[str, Any] = {}

    def swap(slot: int, serial: str, seed: int) -> None:
        fixture.putters.pop(slot).close()
        fixture.plug(slot, serial, seed)

    def operator(app: FixtureApp) -> None:
        step = seen.setdefault("step", 0)
        if step == 0 and app.stage is Stage.CYCLE:
            # While the fixture captures: the next cycle's labels, one refused each way,
            # and the last one queued taken off again and scanned again.
            fixture.keys = [*"".join(f"{label}\r" for label in ahead), "\x7f", *"PT000602\r"]
            seen["step"] = 1
        elif step == 1 and app.stage is Stage.CYCLE and not fixture.keys:
            assert not any(s.run is None for s in app.slots)  # the runs went on
            seen["cycle screen"], seen["step"] = render(app), 2
        elif step == 2 and app.stage is Stage.SCAN:
            seen["scan screen"] = render(app)
            swap(1, "PT000602", seed=602)  # slot 2's unit put in slot 1
            fixture.putters.pop(2).close()
            fixture.keys, seen["step"] = ["\r"], 3
        elif step == 3 and app.scanner.looking is None and not fixture.keys:
            assert app.scanner.current is app.slots[0]  # slot 1 asked again
            assert app.scanner.offered == "PT000601"
            swap(1, "PT000601", seed=601)
            fixture.keys, seen["step"] = ["\r", "-", "\r"], 4  # and slot 2 left empty
        elif step == 4 and app.stage is Stage.CYCLE:
            seen["second"] = {s.number: s.serial for s in app.running}
            for slot in app.running:
                assert slot.run is not None
                slot.run.abort()  # the second cycle's start is what is tested here
            seen["step"] = 5

    fixture.on_tick = operator
    fixture.serve(app)

    assert seen["second"] == {1: "PT000601"}
    assert stored(fixture) == {"PT000501": ("pass", "ship"), "PT000502": ("pass", "ship")}
    lines = fixture.log.getvalue().splitlines()
    for said in (
        "next cycle: slot 1 ← PT000601",
        "PT000501 is in slot 1 now: scan it again once it is out",
        "'nope' is not a serial number (expected ^PT\\d{6}$)",
        "PT000601 is queued for slot 1 already",
        "every slot has its next unit: PT000603 not queued",
        "PT000602 taken off the next cycle (slot 2 is free again)",
        "next cycle: slot 2 ← PT000602",
        "slot 2 left empty: skipped this cycle",
        "PT000602 was not loaded in slot 2: scan it again",
    ):
        assert said in lines
    assert lines.count("next cycle: slot 2 ← PT000602") == 2
    assert any(line.startswith("wrong unit in slot 1: it reports PT000602") for line in lines)
    assert "next cycle: slot 1 ← PT000601, slot 2 ← PT000602" in seen["cycle screen"]
    assert "Put PT000601 in slot 1, then Enter" in seen["scan screen"]
    assert "Traceback" not in fixture.log.getvalue()
