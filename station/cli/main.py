"""Entry point of the ``calstation`` command: assembles the command groups.

Each command lives in its own module, and only the module of the command being run is
imported (the modules pull in scipy, SQLAlchemy, FastAPI and more): ``calstation
solve`` starts without loading the web server, and ``calstation --help``, ``version``
or a mistyped command load none of them: the list of commands is drawn from their
one-line summaries here (a test holds each equal to its command's own help).
Errors meant for a person (:class:`station.domain.errors.CalstationError`) and a command
line the option parser refuses (click's usage errors) end as one line on standard error
and exit status 2; nothing else is caught, so a genuine bug still shows its traceback.
"""

import importlib
import sys
from typing import Any, NamedTuple, NoReturn

import typer

from station import __version__
from station.cli.output import fail, out
from station.domain.errors import CalstationError

EXIT_USER_ERROR = 2
#: The exit status of a command stopped by Ctrl-C (the shell's 128 + SIGINT).
EXIT_INTERRUPTED = 130


class Command(NamedTuple):
    """Where a command lives, and the line ``calstation --help`` shows for it."""

    module: str
    #: A function (one command) or a ``typer.Typer`` (a group).
    attribute: str
    summary: str


#: Every command by name, in the order ``calstation --help`` lists them.
COMMANDS: dict[str, Command] = {
    "run": Command(
        "station.cli.station",
        "run_command",
        "The operator station: scan a unit, take its poses, judge it, store it.",
    ),
    "demo": Command(
        "station.cli.station",
        "demo_command",
        "The station on virtual putters, with a scripted operator: the main job's demo.",
    ),
    "solve": Command(
        "station.cli.solve",
        "solve_command",
        "Compute offsets and sensitivities from still-pose means, in the declared units.",
    ),
    "simulate": Command(
        "station.cli.simulate",
        "simulate",
        "Run a virtual putter that speaks the station's serial protocol.",
    ),
    "serve": Command("station.cli.serve", "serve", "Serve the results API (OpenAPI at /docs)."),
    "report": Command(
        "station.cli.report",
        "report",
        "End-of-line report: yields, failure Pareto, capability, control charts, ship/hold.",
    ),
    "review": Command(
        "station.cli.db",
        "review_command",
        "Review a unit on hold: release it for a retest, or scrap it (recorded, append-only).",
    ),
    "gyro": Command(
        "station.cli.gyro",
        "app",
        "Gyros: fit the g-sensitivity error model, simulate the centrifuge test.",
    ),
    "db": Command(
        "station.cli.db",
        "db_app",
        "The results database: schema migrations, the report's roll-ups, backups.",
    ),
    "keys": Command(
        "station.cli.db",
        "keys_app",
        "API keys of the stations (runs), labs (gyro fits) and quality engineers (reviews of "
        "units on hold) that submit over HTTP.",
    ),
    "certificate": Command(
        "station.cli.certificate",
        "certificate_app",
        "Calibration certificates: issue, sign and verify; authorised signatories' keys.",
    ),
    "outbox": Command(
        "station.cli.outbox",
        "outbox_app",
        "The station's outbox: list, show, resend and send the runs waiting or set aside.",
    ),
}


def _version() -> None:
    """Print the software version."""
    out.print(__version__)


def _root() -> None:
    """Calibration station for the smart putter."""


def _summary_only() -> None:
    """Never runs: ``main`` loads the real command whenever its name is given."""


def build_app(command: str | None = None) -> typer.Typer:
    """The ``calstation`` app with ``command`` loaded; the others by their summary only."""
    app = typer.Typer(
        name="calstation",
        help="Calibration station for the smart putter: solve, simulate, run, serve.",
        no_args_is_help=True,
        add_completion=False,
        pretty_exceptions_enable=False,
        # click's plain help: each flag as it is typed (rich's panels label it <bool>).
        rich_markup_mode=None,
    )
    app.callback()(_root)
    for name, (module, attribute, summary) in COMMANDS.items():
        if name != command:
            app.command(name=name, help=summary)(_summary_only)
            continue
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
        status = build_app(command)(prog_name="calstation", standalone_mode=False)
    except CalstationError as exc:
        fail(str(exc))
        raise SystemExit(EXIT_USER_ERROR) from None
    except typer.TyperException as exc:  # the option parser's refusals (click's, in typer)
        refused(exc)
    except typer.Abort:  # Ctrl-C outside a station's loop
        raise SystemExit(EXIT_INTERRUPTED) from None
    raise SystemExit(status if isinstance(status, int) else 0)


def refused(exc: typer.TyperException) -> NoReturn:
    """A command line the option parser refused, in one line on standard error: the
    command, what is wrong, where its help is; a group given no command shows its help."""
    context: Any = getattr(exc, "ctx", None)
    where = context.command_path if context is not None else "calstation"
    code = getattr(exc, "exit_code", EXIT_USER_ERROR)
    if context is not None and exc.format_message() == context.get_help():
        out.print(exc.format_message(), markup=False, highlight=False)
        raise SystemExit(code)
    problem = " ".join(exc.format_message().replace("Value error, ", "").split())
    fail(f"{where}: {problem} (see {where} --help)")
    raise SystemExit(code)
