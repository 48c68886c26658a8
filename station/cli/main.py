"""Entry point of the ``calstation`` command: assembles the command groups.

Errors meant for a person (:class:`station.errors.CalstationError`) end as one line on
standard error and exit status 2; nothing else is caught, so a genuine bug still shows
its traceback.
"""

import typer

from station import __version__
from station.cli import gyro, solve, station
from station.cli.db import db_app, keys_app
from station.cli.output import fail, out
from station.cli.report import report
from station.cli.serve import serve
from station.cli.simulate import simulate
from station.errors import CalstationError

EXIT_USER_ERROR = 2

app = typer.Typer(
    name="calstation",
    help="Calibration station for the smart putter: solve, simulate, run, serve.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
app.command(name="solve")(solve.solve_command)
app.command(name="run")(station.run_command)
app.command(name="demo")(station.demo_command)
app.add_typer(gyro.app, name="gyro")


@app.callback()
def _root() -> None:
    """Calibration station for the smart putter."""


@app.command()
def version() -> None:
    """Print the software version."""
    out.print(__version__)


app.command()(serve)
app.command()(report)
app.add_typer(db_app, name="db")
app.add_typer(keys_app, name="keys")
app.command()(simulate)


def main() -> None:
    """Run the command line, turning user errors into one line and exit status 2."""
    try:
        app(prog_name="calstation")
    except CalstationError as exc:
        fail(str(exc))
        raise SystemExit(EXIT_USER_ERROR) from None
