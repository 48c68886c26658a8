"""Scanning ahead (:class:`station.loop.fixture.ahead.ScanAhead`): what the queue may hold.

The fixture's end-to-end run with labels scanned ahead is in ``test_fixture.py``, and
across a restart of the station's process in ``test_leaving.py``; here any sequence of
labels, repeats and Backspaces is typed at the queue directly, its files on a real disk.
"""

import itertools
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import cast

from hypothesis import given
from hypothesis import strategies as st

from station.loop.fixture.ahead import ScanAhead
from station.loop.prompt import Label, LabelReader
from station.loop.slot import Slot
from station.results.journal import JournalFile, QueuedLabelFile
from station.run.operator_text import not_a_serial
from station.run.unit_run import UnitRun

PATTERN = r"^PT\d{6}$"


def refuse(text: str) -> str | None:
    """The station's check of a scan without a label form: a serial number."""
    return not_a_serial(text, PATTERN)


def slots(count: int, inside: dict[int, str]) -> list[Slot]:
    """``count`` slots; those in ``inside`` calibrate that serial now."""
    made = [
        Slot(n, f"/dev/null{n}", JournalFile(Path(f"/nonexistent/j{n}")))
        for n in range(1, count + 1)
    ]
    for number, serial in inside.items():
        made[number - 1].begin(serial, cast(UnitRun, object()))
    return made


def label_files(folder: Path, slots: Sequence[Slot]) -> list[QueuedLabelFile]:
    """Where each slot's label scanned ahead is kept, in ``folder``."""
    return [QueuedLabelFile(folder / f"next-unit-slot{s.number}.txt") for s in slots]


labels = st.sampled_from(["PT000001", "PT000002", "PT000003", "PT000004", "PT000005", "nope"])


@given(
    count=st.integers(min_value=1, max_value=4),
    inside=st.dictionaries(st.integers(min_value=1, max_value=4), labels, max_size=2),
    typed=st.lists(labels | st.just("\x7f"), max_size=20),
)
def test_the_queue_holds_each_serial_once_in_the_lowest_free_slots(
    count: int, inside: dict[int, str], typed: list[str]
) -> None:
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        fixture = slots(count, {n: s for n, s in inside.items() if n <= count})
        said: list[str] = []
        ahead = ScanAhead(
            fixture, tell=said.append, refuse=refuse, files=label_files(folder, fixture)
        )
        expected: list[str] = []  # the model: serials in scan order, slots 1, 2, ... in turn
        running = {s.serial for s in fixture if s.run is not None}
        for entry in typed:
            before, lines = len(said), 1  # one line for every label, and every label taken off
            ahead.scanned(entry if entry == "\x7f" else Label(entry))
            if entry == "\x7f":
                lines = int(bool(expected))
                expected = expected[:-1]
            elif entry != "nope" and entry not in expected and entry not in running:
                expected += [entry][: count - len(expected)]
            assert len(said) == before + lines, said
            assert list(ahead.queued.values()) == expected
            assert sorted(ahead.queued) == list(range(1, len(expected) + 1))
            # What a station started again reads from the files is the queue, in its order.
            again = ScanAhead(
                fixture, tell=said.append, refuse=refuse, files=label_files(folder, fixture)
            )
            assert list(again.queued.items()) == list(ahead.queued.items())
        offered = [ahead.offered(s) for s in fixture]
        assert [o for o in offered if o is not None] == expected
        for slot in fixture:
            ahead.settled(slot)
        assert not ahead.queued
        assert not list(folder.iterdir())


def test_each_refusal_says_why_in_one_line(tmp_path: Path) -> None:
    fixture = slots(2, {1: "PT000001"})
    said: list[str] = []
    ahead = ScanAhead(
        fixture, tell=said.append, refuse=refuse, files=label_files(tmp_path, fixture)
    )
    for label in ("PT000009", "PT000001", "nope", "PT000009", "PT000008", "PT000007", "\x7f"):
        ahead.scanned(label if label == "\x7f" else Label(label))
    assert said == [
        "next cycle: slot 1 ← PT000009",
        "PT000001 is in slot 1 now: scan it again once it is out",
        "'nope' is not a serial number (expected ^PT\\d{6}$)",
        "PT000009 is queued for slot 1 already",
        "next cycle: slot 2 ← PT000008",
        "every slot has its next unit: PT000007 not queued",
        "PT000008 taken off the next cycle (slot 2 is free again)",
    ]


@given(
    label=st.text(alphabet="aPT0123456789h?-", min_size=2, max_size=12),
    cuts=st.lists(st.integers(min_value=1, max_value=11), max_size=4),
)
def test_a_scanned_label_is_one_label_however_the_burst_arrives(
    label: str, cuts: list[int]
) -> None:
    """A label and Enter typed as one burst, cut into any pieces of two keys or more (a
    scanner's keys arrive together), is that label, never a key: whatever its letters."""
    burst = label + "\r"
    edges = sorted({0, len(burst), *(c for c in cuts if c < len(burst))})
    pieces = [burst[a:b] for a, b in itertools.pairwise(edges)]
    if any(len(piece) < 2 for piece in pieces):
        pieces = [burst]
    reader = LabelReader("ah?")
    events = [event for piece in pieces for event in reader.feed(piece)]
    assert events == [Label(label)]
    assert reader.typed == ""


def test_a_key_alone_is_a_key_and_a_label_being_typed_takes_every_key() -> None:
    reader = LabelReader("ah?")
    assert reader.feed("a") == ["a"]
    assert reader.feed("x") == []  # not a command: a label begins
    assert reader.feed("a") == []  # a label is being typed: its keys are the label's
    assert reader.feed("\x7f") == []
    assert reader.typed == "x"
    assert reader.feed("\x7f") == []
    assert reader.feed("\x7f") == ["\x7f"]  # an empty line: Backspace is a key
