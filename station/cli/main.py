"""Entry point of the ``calstation`` command: assembles the command groups.

Each command lives in its own module, and only the module of the command being run is
imported (the modules pull in scipy, SQLAlchemy, FastAPI and more): ``calstation
solve`` starts without loading the web server; ``calstation --help`` loads them all.
Errors meant for a person (:class:`station.domain.errors.CalstationError`) end as one line on
standard error and exit status 2; nothing else is caught, so a genuine bug still shows
its traceback.
"""

import importlib
import sys

import typer

from station import __version__
from station.cli.output import fail, out
from station.domain.errors import CalstationError

EXIT_USER_ERROR = 2

#: Command name → (module, attribute): a function (one command) or a ``typer.Typer``.
COMMANDS: dict[str, tuple[str, str]] = {
    "run": ("station.cli.station", "run_command"),
    "demo": ("station.cli.station", "demo_command"),
    "solve": ("station.cli.solve", "solve_command"),
    "simulate": ("station.cli.simulate", "simulate"),
    "serve": ("station.cli.serve", "serve"),
    "report": ("station.cli.report", "report"),
    "gyro": ("station.cli.gyro", "app"),
    "db": ("station.cli.db", "db_app"),
    "keys": ("station.cli.db", "keys_app"),
    "review": ("station.cli.db", "review_command"),
    "outbox": ("station.cli.outbox", "outbox_app"),
}


def _version() -> None:
    """Print the software version."""
    out.print(__version__)


def _root() -> None:
    """Calibration station for the smart putter."""


def _needed(command: str | None) -> list[str]:
    """The commands to load for ``command``: itself, none for ``version``, else all."""
    if command in COMMANDS:
        return [command]
    if command == "version":
        return []
    return list(COMMANDS)


def build_app(command: str | None = None) -> typer.Typer:
    """The ``calstation`` app with ``command`` (every command when it names none of them)."""
    app = typer.Typer(
        name="calstation",
        help="Calibration station for the smart putter: solve, simulate, run, serve.",
        no_args_is_help=True,
        add_completion=False,
        pretty_exceptions_enable=False,
    )
    app.callback()(_root)
    for name in _needed(command):
        module, attribute = COMMANDS[name]
        target = getattr(importlib.import_module(module), attribute)
        if isinstance(target, typer.Typer):
            app.add_typer(target, name=name)
        else:
            app.command(name=name)(target)
    app.command(name="version")(_version)
    return app


def main() -> None:
    """Run the command line, turning user errors into one line and exit status 2."""
    command = sys.argv[1] if len(sys.argv) > 1 else None
    try:
        build_app(command)(prog_name="calstation")
    except CalstationError as exc:
        fail(str(exc))
        raise SystemExit(EXIT_USER_ERROR) from None
