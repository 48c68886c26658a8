"""``calstation outbox``: what waits to be stored, what was set aside and why; resend it."""

# Light to import: --help and refused arguments read only the signatures below;
# each command imports its work (numpy, SQLAlchemy, the loop, ...) when it runs.

from __future__ import annotations

import json
from contextlib import suppress
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from station.cli.output import out
from station.domain.errors import InputError

if TYPE_CHECKING:
    from station.loop.config import StationConfig
    from station.results.outbox import Outbox
    from station.results.outbox_admin import Entry

outbox_app = typer.Typer(
    help="The station's outbox: list, show, resend and send the runs waiting or set aside.",
    no_args_is_help=True,
)

ConfigOption = Annotated[
    Path | None, typer.Option("--config", help="Station configuration (TOML), as for run.")
]
DataDirOption = Annotated[
    Path | None,
    typer.Option("--data-dir", help="The station's data directory (default: as calstation run)."),
]


def _outbox(config_file: Path | None, data_dir: Path | None) -> Outbox:
    """The outbox of the station configured as ``calstation run`` would find it."""
    from station.loop.config import load_config

    return _outbox_of(load_config(config_file, {"data_dir": data_dir}))


def _outbox_of(config: StationConfig) -> Outbox:
    """The outbox of the station ``config`` describes."""
    from station.results.outbox import Outbox

    directory = config.outbox_dir
    if not directory.is_dir():
        raise InputError(f"no outbox at {directory} (is --data-dir right?)")
    return Outbox(directory)


def _line(entry: Entry) -> str:
    s = entry.summary
    fields = [f"{entry.state:<10}", f"{s.run_id:<36}", f"{s.serial or '-':<10}"]
    fields.append(f"{s.verdict or '-':<4}")
    return ("  ".join(fields) + (f"  {entry.reason}" if entry.reason else "")).rstrip()


@outbox_app.command("list")
def list_command(config_file: ConfigOption = None, data_dir: DataDirOption = None) -> None:
    """Every run waiting, unreadable or refused, with the reason it was set aside."""
    from station.results.outbox_admin import entries

    outbox = _outbox(config_file, data_dir)
    found = entries(outbox)
    for entry in found:
        out.print(_line(entry), markup=False)
    counts = {
        state: sum(e.state == state for e in found)
        for state in ("waiting", "unreadable", "refused")
    }
    out.print(
        f"{counts['waiting']} waiting, {counts['unreadable']} unreadable, "
        f"{counts['refused']} refused in {outbox.directory}",
        markup=False,
    )


@outbox_app.command("show")
def show_command(
    run_id: Annotated[str, typer.Argument(help="Run id (or its first characters).")],
    config_file: ConfigOption = None,
    data_dir: DataDirOption = None,
) -> None:
    """One run's record as stored in the outbox, and why it was set aside."""
    from station.results.outbox_admin import find
    from station.results.outbox_files import UnreadableRecordError, read_bytes

    entry = find(_outbox(config_file, data_dir), run_id)
    out.print(f"{entry.state}: {entry.path}", markup=False)
    if entry.reason:
        out.print(f"reason: {entry.reason}", markup=False)
    try:
        data = read_bytes(entry.path)
    except UnreadableRecordError as exc:
        out.print(f"({exc})", markup=False)
        return
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        out.print(f"({len(data)} bytes, not text)", markup=False)
        return
    with suppress(ValueError):  # a torn or garbled record is shown as it is
        text = json.dumps(json.loads(text), indent=2)
    out.print(text, markup=False, highlight=False)


@outbox_app.command("resend")
def resend_command(
    run_id: Annotated[str | None, typer.Argument(help="Run id (or its first characters).")] = None,
    every: Annotated[bool, typer.Option("--all", help="Every run set aside.")] = False,
    config_file: ConfigOption = None,
    data_dir: DataDirOption = None,
) -> None:
    """Put set-aside runs back into the queue; the station sends them at its next sync."""
    if (run_id is None) == (not every):
        raise InputError("give one run id, or --all")
    from station.results.outbox_admin import entries, find, resend

    outbox = _outbox(config_file, data_dir)
    if run_id is not None:
        entry = find(outbox, run_id)
        if entry.state == "waiting":
            out.print(f"run {entry.path.stem} already waits in the outbox", markup=False)
            return
        resend(outbox, entry)
        out.print(f"run {entry.path.stem} back in the outbox ({entry.state} before)", markup=False)
        return
    moved = 0
    for entry in entries(outbox):
        if entry.state == "waiting":
            continue
        try:
            resend(outbox, entry)
        except InputError as exc:
            out.print(str(exc), markup=False)
        else:
            moved += 1
    out.print(f"{moved} run{'s' * (moved != 1)} back in the outbox", markup=False)


@outbox_app.command("send")
def send_command(
    run_id: Annotated[str, typer.Argument(help="Run id (or its first characters).")],
    api_key: Annotated[
        str,
        typer.Option(
            "--api-key",
            envvar="CALSTATION_SEND_API_KEY",
            help="The key of the station that recorded the run (a renamed station's former name).",
        ),
    ],
    server: Annotated[
        str | None, typer.Option("--server", help="Results server URL (default: the config's).")
    ] = None,
    config_file: ConfigOption = None,
    data_dir: DataDirOption = None,
) -> None:
    """Store one run now with the given key, waiting or set aside; the file goes once stored."""
    from station.loop.config import load_config
    from station.results.outbox_admin import find, send
    from station.results.storage import HttpStore

    config = load_config(
        config_file, {"data_dir": data_dir, "server_url": server, "api_key": api_key}
    )
    if not config.server_url:
        raise InputError("no results server: give --server URL or set server_url")
    entry = find(_outbox_of(config), run_id)
    with HttpStore(config.server_url, api_key) as store:
        outcome = send(entry, store)
    said = "stored" if outcome.created else "already stored"
    out.print(f"run {entry.summary.run_id} {said} ({entry.state} before)", markup=False)
