"""What the operator sees: rich renderables built from the station's state.

Pure functions of their arguments (no I/O), so the same screens serve the live
terminal, the demo's scripted operator and the tests.
"""

from dataclasses import dataclass

from rich.align import Align
from rich.cells import cell_len
from rich.columns import Columns
from rich.console import Console, ConsoleOptions, Group, RenderableType, RenderResult
from rich.panel import Panel
from rich.table import Table
from rich.text import Text

from station.domain.i18n import tr
from station.domain.record.records import RunRecord
from station.domain.signals.poses import Pose
from station.report.explanations import explanation
from station.run.operator_text import (
    pose_instruction,
    pose_words,
    said_of,
    verdict_word,
    wrong_unit,
)
from station.run.phases import Phase
from station.run.view import RunView


def drawing(name: str) -> str:
    """A small drawing of the putter in the pose ``name`` (head ▣, shaft ║ or ═, grip ▓),
    its words in the operator's language ("" for a pose without one)."""
    drawings = {
        "face_up": "   " + tr("face") + " ↑\n ▣═════════▓\n " + tr("(lying on its back)"),
        "face_down": " ▣═════════▓\n   " + tr("face") + " ↓\n " + tr("(lying face down)"),
        "toe_up": "  " + tr("toe") + " ↑\n  ▣═════════▓\n  " + tr("heel on the table"),
        "toe_down": "  " + tr("heel") + " ↑\n  ▣═════════▓\n  " + tr("toe on the table"),
        "shaft_up": "  ▓\n  ║\n  ║\n  ▣  " + tr("head down, shaft up"),
        "shaft_down": "  ▣  " + tr("head up, grip down") + "\n  ║\n  ║\n  ▓",
        "verify_tilted": "     ▓\n    ╱\n   ╱\n  ▣   " + tr("tilted cradle"),
    }
    return drawings.get(name, "")


BANNER = {
    "pass": (
        " ████   ███   ████  ████ ",
        " █   █ █   █ █     █     ",
        " ████  █████  ███   ███  ",
        " █     █   █     █     █ ",
        " █     █   █ ████  ████  ",
    ),
    "fail": (
        " █████  ███  ███ █     ",
        " █     █   █  █  █     ",
        " ████  █████  █  █     ",
        " █     █   █  █  █     ",
        " █     █   █ ███ █████ ",
    ),
}


def next_step(disposition: str) -> tuple[str, str]:
    """What a disposition tells the operator, under the verdict, and its colour."""
    return {
        "ship": (
            tr("SHIP: the unit holds verified coefficients; put it with the good units"),
            "green",
        ),
        "retest": (tr("RETEST: calibrate this unit again"), "yellow"),
        "rework": (
            tr("REWORK: take the unit to the repair bench; do not calibrate it again"),
            "red",
        ),
    }[disposition]


def keys_help() -> str:
    """The keys, in one line under the unit's screen."""
    return tr(
        "keys: r redo last pose · 1-9 redo a pose already taken (✓) · a abort unit · h help · "
        "scan the next unit's label any time"
    )


#: What stands between two keys of a keys line, in every language.
KEY_SEPARATOR = "·"


@dataclass(frozen=True)
class KeysLine:
    """A keys line (:func:`keys_help`) wrapped between its keys, never inside one: as
    many keys to a line as the width holds ("r redo last pose" stays together), a key
    wider than the whole width folded on its own lines."""

    line: str
    style: str = "dim"

    @property
    def keys(self) -> list[str]:
        """Each key with what it does, as the line lists them."""
        return [key.strip() for key in self.line.split(KEY_SEPARATOR) if key.strip()]

    def __rich_console__(self, console: Console, options: ConsoleOptions) -> RenderResult:
        joint = f" {KEY_SEPARATOR} "
        lines: list[str] = []
        for key in self.keys:
            if lines and cell_len(lines[-1] + joint + key) <= options.max_width:
                lines[-1] += joint + key
            else:
                lines.append(key)
        for line in lines:
            yield Text(line, style=self.style)


def help_text() -> str:
    """The help the h key shows."""
    return tr(
        "The station asks for one pose at a time. Put the putter in the pose shown, let go,\n"
        "and keep hands off: the capture starts by itself once it lies still in that pose.\n"
        "\n"
        "  r      redo the last pose taken (then y to confirm)\n"
        "  1…9    redo pose number N, once taken (then y; its old capture is kept for audit)\n"
        "  a      abort this unit (press a, then y to confirm)\n"
        "  h, ?   show or hide this help\n"
        "\n"
        "A label scanned during a unit is the next unit's: Enter at the serial prompt takes it.\n"
        "\n"
        "At the serial prompt: scan the label (or type it and press Enter); type quit to stop."
    )


def header(
    station_id: str,
    operator_id: str,
    versions: str,
    backlog: int,
    set_aside: tuple[int, int] = (0, 0),
) -> RenderableType:
    """The top lines: who, how many runs wait in the outbox (and were set aside), versions."""
    backlog_text = tr("outbox {count}", count=backlog) if backlog else tr("outbox empty")
    style = "bold yellow" if backlog else "green"
    unreadable, refused = set_aside
    aside = [tr("{count} unreadable", count=unreadable)] if unreadable else []
    aside += [tr("{count} refused", count=refused)] if refused else []
    who = Text.assemble(
        ("calstation", "bold"),
        " · ",
        tr("station {station} · operator {operator}", station=station_id, operator=operator_id),
        " · ",
        (backlog_text, style),
        (f" · {' · '.join(aside)} (calstation outbox list)" if aside else "", "bold red"),
    )
    return Group(who, Text(versions, style="dim"))


def _meter(value: float, limit: float, label: str, width: int, unit: str) -> Text:
    """``label`` in ``width`` cells, then a bar of ``value`` against ``limit``."""
    ratio = min(value / limit, 2.0) if limit > 0 else 0.0
    filled = round(ratio * 10)
    style = "green" if ratio <= 1 else "red"
    bar = "▇" * min(filled, 20) + "·" * max(0, 10 - filled)
    return Text.assemble(pad(label, width), (bar, style), f" {value:5.2f} / {limit:g} {unit}")


def pad(text: str, cells: int) -> str:
    """``text`` padded with spaces to ``cells`` terminal cells (a Korean or Chinese
    character takes two)."""
    return text + " " * max(0, cells - cell_len(text))


def pose_strip(view: RunView) -> RenderableType:
    """Every pose of the run, ✓ taken, ▶ asked, · to come: as many to a line as the
    terminal holds, a pose never split over two lines."""
    items = []
    for i, p in enumerate(view.poses):
        mark = "✓" if i in view.taken else ("▶" if i == view.index else "·")
        style = "green" if mark == "✓" else ("bold cyan" if mark == "▶" else "dim")
        items.append(Text(f"{mark}{i + 1} {pose_words(p.name)}", style=style))
    return Columns(items, padding=(0, 1))


def unit_screen(view: RunView, show_help: bool = False) -> RenderableType:
    """The screen while a unit is calibrated, drawn from the run's view model."""
    total = len(view.poses)
    target: Pose | None = view.requested
    parts: list[RenderableType] = []
    title = tr("unit {serial}", serial=view.serial)
    if view.phase is Phase.RECONNECT and view.wrong_unit is not None:
        parts.append(Text(wrong_unit(view.wrong_unit, view.serial).upper(), style="bold red"))
    elif view.phase is Phase.RECONNECT:
        parts.append(
            Text(
                tr("CABLE PULLED — plug the unit back in; the poses taken are kept"),
                style="bold red",
            )
        )
    elif view.phase is Phase.UNIT_OUTPUT:
        parts.append(
            Text(tr("checking the unit's own calibrated output — keep it still"), style="bold")
        )
    elif target is not None:
        step = Text.assemble(
            (
                tr(
                    "pose {number} of {total}: {pose}",
                    number=view.index + 1,
                    total=total,
                    pose=pose_words(target.name),
                ),
                "bold cyan",
            ),
            f" — {pose_instruction(target)}",
        )
        parts.append(step)
        parts.append(Text(drawing(target.name), style="cyan"))
        live = view.live
        if live.sensed is not None:
            ok = tr("✓ matches") if live.matches else tr("✗ not the pose asked for")
            parts.append(
                Text.assemble(
                    tr("station sees: "),
                    (pose_words(live.sensed.nearest.name), "bold"),
                    tr(" ({degrees}° off)  ", degrees=f"{live.sensed.nearest_deg:.0f}"),
                    (ok, "green" if live.matches else "red"),
                )
            )
        limits = view.stillness
        accel, gyro = tr("accel"), tr("gyro")
        width = max(cell_len(accel), cell_len(gyro)) + 1  # the bars start in one column
        parts.append(
            _meter(
                float(live.accel_std.max()), limits.accel_std_max_counts, accel, width, tr("counts")
            )
        )
        parts.append(
            _meter(float(abs(live.gyro_rate).max()), limits.gyro_rate_max_dps, gyro, width, "deg/s")
        )
        state = tr("moving") if live.moving else tr("still")
        filled = round(live.progress * 30)
        refused = live.refused is not None and live.progress >= 1.0
        parts.append(
            Text.assemble(
                tr("capture ({state}) ", state=state),
                ("█" * filled, "red" if refused else "green"),
                ("░" * (30 - filled), "dim"),
                " " + tr("refused") if refused else f" {live.progress:4.0%}",
            )
        )
        if live.refused is not None:
            parts.append(Text(live.refused, style="bold yellow"))
    parts.append(pose_strip(view))
    for message in view.messages:
        style = {"info": "white", "warn": "yellow", "error": "bold red"}.get(message.level, "white")
        parts.append(Text(message.text, style=style))
    parts.append(Text(help_text(), style="dim") if show_help else KeysLine(keys_help()))
    return Panel(Group(*parts), title=title, border_style="cyan")


def verdict_screen(record: RunRecord) -> RenderableType:
    """The large PASS or FAIL banner with every failing check named."""
    style = "bold white on green" if record.verdict == "pass" else "bold white on red"
    big = Text("\n".join(BANNER[record.verdict]), style=style, justify="left", no_wrap=True)
    lines: list[RenderableType] = [
        Align.center(big),
        Text(
            tr(
                "{verdict}  unit {serial}",
                verdict=verdict_word(record.verdict),
                serial=record.serial,
            ),
            style="bold",
            justify="center",
        ),
    ]
    if record.coefficients is not None:
        c = record.coefficients
        table = Table(box=None, show_header=True, pad_edge=False)
        table.add_column(tr("axis"))
        table.add_column(tr("offset (counts)"), justify="right")
        table.add_column(tr("sensitivity (counts/g)"), justify="right")
        for axis in ("x", "y", "z"):
            table.add_row(
                axis, f"{getattr(c.offset, axis):.2f}", f"{getattr(c.sensitivity, axis):.2f}"
            )
        lines.append(Align.center(table))
    for failure in record.failures:
        lines.append(Text("✗ " + said_of(failure.code, explanation(failure)), style="red"))
    if record.disposition is not None:
        step, colour = next_step(record.disposition)
        lines.append(Text(tr("next: {step}", step=step), style=f"bold {colour}", justify="center"))
    lines.append(Text(tr("run {run_id}", run_id=record.run_id), style="dim", justify="center"))
    return Panel(Group(*lines), border_style="green" if record.verdict == "pass" else "red")


def serial_prompt(typed: str, note: str | None, queued: str | None = None) -> RenderableType:
    """The prompt for the next unit's serial number (``queued``: scanned during the last
    unit, taken by Enter)."""
    take = tr(" (Enter: {serial}, scanned during the last unit)", serial=queued) if queued else ""
    asked = said_of(tr("Scan the next unit's serial number") + take, "")
    parts: list[RenderableType] = [Text.assemble((asked, "bold"), typed, ("█", "blink"))]
    if note:
        parts.append(Text(note, style="yellow"))
    return Group(*parts)
