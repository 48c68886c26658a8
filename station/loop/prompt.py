"""What the station waits for from the operator, and what the keys typed mean.

:class:`Prompt` holds the questions the station has asked (resume an interrupted unit?
calibrate a passed unit again? abort this unit? take this pose again?), the serial number
typed so far and the note shown under the prompt. It turns keys into answers
(:data:`Answer`) for the station's loop (:class:`station.loop.app.StationApp`), which acts
on them; keys during a unit go to the run (redo, abort, each asked first) or toggle the
help. It draws its part of the screen (:meth:`Prompt.screen`): the question asked, the
unit in progress, or the last verdict and the serial prompt.

**A scanner is not a keyboard** (:class:`LabelReader`). A barcode scanner types a label
and Enter in one burst; an operator presses one key. During a unit a key acts only when
it arrives alone, is one of the unit's keys, and no label is being typed; anything else
is a label, queued as the next unit (Enter at the serial prompt takes it). So the next
unit's label scanned during a run never redoes a pose, and a key that would throw away
work (a redo, an abort) asks first.
"""

from dataclasses import dataclass
from enum import StrEnum

from rich.console import Group, RenderableType
from rich.text import Text

from station.domain.i18n import tr
from station.domain.record.records import RunRecord
from station.loop.screens import serial_prompt, unit_screen, verdict_screen
from station.results.journal import RunJournal
from station.run.operator_text import pose_words
from station.run.unit_run import UnitRun
from station.run.view import RunView

ENTER = ("\r", "\n")
BACKSPACE = ("\x7f", "\b")
#: The keys that act on the unit in progress when pressed alone.
UNIT_KEYS = "r123456789ah?"


class State(StrEnum):
    """What the station waits for."""

    RESUME = "resume"
    SERIAL = "serial"
    #: A scanned unit's history is being looked up (keys wait until it is in).
    LOOKING = "looking"
    CONFIRM = "confirm"
    UNIT = "unit"


@dataclass(frozen=True)
class Serial:
    """A serial number typed (or scanned) and entered."""

    text: str


@dataclass(frozen=True)
class Resume:
    """The answer to "resume the interrupted unit?": ``yes`` (resume) or not (discard)."""

    journal: RunJournal
    yes: bool


@dataclass(frozen=True)
class Recalibrate:
    """The answer to "passed already: calibrate again?"."""

    yes: bool


Answer = Serial | Resume | Recalibrate


@dataclass(frozen=True)
class Label:
    """A label scanned (or typed and entered) while keys act on something else."""

    text: str


class LabelReader:
    """Tells labels from keys: a key is a key only when it arrives alone (nothing else
    typed since the last look), is one of ``commands``, and no label is being typed;
    everything else is typed into a label, which Enter ends and Backspace edits (a
    Backspace on an empty line is a key)."""

    def __init__(self, commands: str) -> None:
        self.commands = commands
        #: The label typed so far.
        self.typed = ""

    def feed(self, chunk: str) -> list[str | Label]:
        """The keys and labels of ``chunk``, everything typed since the last look."""
        events: list[str | Label] = []
        for key in chunk:
            if key in ENTER:
                if self.typed.strip():
                    events.append(Label(self.typed.strip()))
                self.typed = ""
            elif key in BACKSPACE and self.typed:
                self.typed = self.typed[:-1]
            elif self.typed or len(chunk) > 1 or key not in (*self.commands, *BACKSPACE):
                if key.isprintable():
                    self.typed += key
            else:
                events.append(key)
        return events


def edit_line(typed: str, key: str) -> tuple[str, str | None]:
    """The line typed so far after ``key``, and the line entered (stripped) on Enter."""
    if key in ENTER:
        return "", typed.strip()
    if key in BACKSPACE:
        return typed[:-1], None
    return (typed + key if key.isprintable() else typed), None


class Prompt:
    """The question asked, the serial typed so far, the note under the prompt."""

    def __init__(self) -> None:
        self.state = State.SERIAL
        self.typed = ""
        self.note: str | None = None
        #: The journal of an interrupted unit, while RESUME asks about it.
        self.pending_resume: RunJournal | None = None
        self.show_help = False
        self.confirm_abort = False
        #: The pose a redo key asked about (the question waits for y).
        self.confirm_redo: int | None = None
        #: The next unit's label, scanned during the last unit (Enter takes it).
        self.next_serial: str | None = None

    def ask_resume(self, journal: RunJournal) -> None:
        """Ask whether to resume the unit ``journal`` left at a crash."""
        self.pending_resume = journal
        self.state = State.RESUME

    @property
    def asking(self) -> bool:
        """Whether a question about the unit in progress waits for its answer."""
        return self.confirm_abort or self.confirm_redo is not None

    def unit_done(self) -> None:
        """The unit ended: back to the serial prompt, questions and help closed."""
        self.state = State.SERIAL
        self.confirm_abort = False
        self.confirm_redo = None
        self.show_help = False

    def screen(
        self, run: RunView | None, last_record: RunRecord | None, label: str = ""
    ) -> RenderableType:
        """The part of the screen under the header: the question asked, or the unit."""
        parts: list[RenderableType] = []
        if self.state is State.RESUME and self.pending_resume is not None:
            j = self.pending_resume
            parts.append(
                Text(
                    tr(
                        "Unit {serial} was interrupted at pose {number} of {total}. "
                        "Resume it? press y (resume) or n (discard)",
                        serial=j.serial,
                        number=j.next_pose + 1,
                        total=len(j.poses),
                    ),
                    style="bold yellow",
                )
            )
        elif self.state is State.CONFIRM and self.note:
            parts.append(Text(self.note, style="bold yellow"))
        elif self.state is State.UNIT and run is not None:
            parts.append(unit_screen(run, self.show_help))
            if self.confirm_abort:
                parts.append(
                    Text(
                        tr("abort this unit? press y to confirm, any other key to go on"),
                        style="bold red",
                    )
                )
            if self.confirm_redo is not None:
                index = self.confirm_redo
                parts.append(
                    Text(
                        tr(
                            "take pose {number} ({pose}) again? "
                            "press y to confirm, any other key to go on",
                            number=index + 1,
                            pose=pose_words(run.poses[index].name),
                        ),
                        style="bold red",
                    )
                )
            if label or self.next_serial:
                shown = (
                    f"{label}█"
                    if label
                    else tr("{serial} (Enter at the prompt)", serial=self.next_serial)
                )
                parts.append(Text(tr("next unit: {unit}", unit=shown), style="bold"))
        else:
            if last_record is not None:
                parts.append(verdict_screen(last_record))
            parts.append(serial_prompt(self.typed, self.note, self.next_serial))
        return Group(*parts)

    def key(self, key: str, run: UnitRun | None) -> Answer | None:
        """What ``key`` answers (None: nothing to act on, or acted on ``run`` already)."""
        if self.state is State.RESUME:
            journal = self.pending_resume
            self.pending_resume = None
            self.state = State.SERIAL
            return None if journal is None else Resume(journal, key.lower() == "y")
        if self.state is State.SERIAL:
            return self._serial_key(key)
        if self.state is State.CONFIRM:
            self.state = State.SERIAL
            return Recalibrate(key.lower() == "y")
        if run is not None:
            self._unit_key(run, key)
        return None

    def _serial_key(self, key: str) -> Serial | None:
        self.typed, entered = edit_line(self.typed, key)
        if entered is None:
            return None
        text, self.next_serial = entered or self.next_serial, None
        return Serial(text) if text else None

    def _unit_key(self, run: UnitRun, key: str) -> None:
        if self.confirm_abort:
            self.confirm_abort = False
            if key.lower() == "y":
                run.abort()
            return
        if self.confirm_redo is not None:
            index, self.confirm_redo = self.confirm_redo, None
            if key.lower() == "y":
                run.redo(index)
            return
        if key in ("h", "?"):
            self.show_help = not self.show_help
        elif key == "r" and run.latest_pose is not None:
            self._ask_redo(run, run.latest_pose)
        elif key.isdigit() and key != "0":
            self._ask_redo(run, int(key) - 1)
        elif key == "a":
            self.confirm_abort = True

    def _ask_redo(self, run: UnitRun, index: int) -> None:
        """Ask before taking a pose again; a pose that cannot be is refused by the run."""
        if run.redoable(index):
            self.confirm_redo = index
        else:
            run.redo(index)
