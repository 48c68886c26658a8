"""``calstation report``: the end-of-line report from the results database."""

# Light to import: --help and refused arguments read only the signatures below;
# each command imports its work (numpy, SQLAlchemy, the loop, ...) when it runs.

from pathlib import Path
from typing import Annotated

import typer

from station.cli.db import DatabaseUrlOption
from station.cli.output import err, out
from station.domain.constants import FORMATS
from station.domain.errors import CalstationError


def report(
    since: Annotated[
        str | None,
        typer.Option("--from", help="Start: ISO date or time, UTC unless a zone is given."),
    ] = None,
    until: Annotated[str | None, typer.Option("--to", help="End (exclusive).")] = None,
    station: Annotated[str | None, typer.Option(help="Only this station.")] = None,
    operator: Annotated[str | None, typer.Option(help="Only this operator.")] = None,
    lot: Annotated[str | None, typer.Option(help="Only this production lot.")] = None,
    part_number: Annotated[
        str | None, typer.Option("--part-number", help="Only this product (part number).")
    ] = None,
    format: Annotated[
        str, typer.Option("--format", help=f"One of: {', '.join(FORMATS)}.")
    ] = "text",
    units: Annotated[
        int | None, typer.Option(min=1, help="List only the latest N units.", show_default=False)
    ] = None,
    limits: Annotated[
        Path | None,
        typer.Option(
            "--limits",
            help="What-if: re-judge the runs against this limits file's profile (its only "
            "one, or kxm52-production): yields, Pareto and Cp/Cpk beside the current ones; "
            "nothing stored changes.",
            show_default=False,
        ),
    ] = None,
    timezone: Annotated[
        str,
        typer.Option(
            "--timezone",
            envvar="CALSTATION_PLANT_TIMEZONE",
            help="The plant's time zone (IANA name): days and times shown in it, "
            "--from/--to without a zone read in it.",
        ),
    ] = "UTC",
    shifts: Annotated[
        str,
        typer.Option(
            "--shifts",
            envvar="CALSTATION_PLANT_SHIFTS",
            help="The plant's shift start times in its zone (e.g. 06:00,14:00,22:00): "
            "a trend per shift too.",
        ),
    ] = "",
    output: Annotated[
        Path | None,
        typer.Option("--out", help="Write to this file instead of standard output."),
    ] = None,
    database_url: DatabaseUrlOption = None,
) -> None:
    """End-of-line report: yields, failure Pareto, capability, control charts, ship/hold."""
    if format not in FORMATS:
        raise CalstationError(f"--format {format!r} is not one of {', '.join(FORMATS)}")
    from sqlalchemy.exc import OperationalError

    from db import DatabaseSettings, DatabaseUnavailableError, open_database
    from db.report import eol_report
    from station.domain.product.limits import load_profile
    from station.domain.quality.figures import ReportFilter
    from station.domain.quality.shifts import parse_shifts
    from station.report.period import parse_period, plant_zone
    from station.report.render import render

    zone = plant_zone(timezone)
    starts = parse_shifts(shifts)
    start, end = parse_period(since, until, zone=zone)
    report_filter = ReportFilter(
        since=start,
        until=end,
        station_id=station,
        operator_id=operator,
        lot=lot,
        part_number=part_number,
    )
    profile = None if limits is None else load_profile(limits)
    url = database_url or DatabaseSettings.from_environment().url()
    database = open_database(url)
    try:
        with database.session() as session:
            report_ = eol_report(
                session,
                report_filter,
                candidate=profile,
                unit_limit=units,
                zone=zone,
                shifts=starts,
            )
    except OperationalError as exc:
        raise DatabaseUnavailableError.of(url, exc) from None
    finally:
        database.dispose()
    text = render(report_, format)
    if output is None:
        out.file.write(text)
        out.file.flush()
        return
    try:
        output.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise CalstationError(f"{output}: cannot write the report: {exc.strerror}") from None
    err.print(f"report written to {output}", markup=False)
