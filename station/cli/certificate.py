"""``calstation certificate issue SERIAL``: the station's own calibration certificate of a
unit, from its results database, as the results server's page shows it."""

# Light to import: --help and refused arguments read only the signatures below; each
# command imports its work (SQLAlchemy, the pages) when it runs.

from pathlib import Path
from typing import Annotated

import typer

from station.cli.db import DatabaseUrlOption
from station.cli.output import err, out
from station.domain.errors import CalstationError, InputError

certificate_app = typer.Typer(
    help="Calibration certificates: issue a unit's from the results database.",
    no_args_is_help=True,
)


@certificate_app.command("issue")
def issue(
    serial: Annotated[str, typer.Argument(metavar="SERIAL", help="The unit's serial number.")],
    config: Annotated[
        Path | None,
        typer.Option(
            "--config",
            help="The station's configuration (TOML) whose [laboratory] table names the "
            "laboratory, its address, where it calibrates, the customer and the traceability "
            "of its reference.",
            show_default=False,
        ),
    ] = None,
    language: Annotated[
        str, typer.Option("--language", help="The reader's language: en, ko or zh.")
    ] = "en",
    timezone: Annotated[
        str,
        typer.Option(
            "--timezone",
            envvar="CALSTATION_PLANT_TIMEZONE",
            help="The plant's time zone (IANA name): times shown in it.",
        ),
    ] = "UTC",
    shifts: Annotated[
        str,
        typer.Option(
            "--shifts",
            envvar="CALSTATION_PLANT_SHIFTS",
            help="The plant's shift start times: the shift whose golden-unit check is the "
            "reference.",
        ),
    ] = "",
    output: Annotated[
        Path | None,
        typer.Option("--out", help="Write to this file instead of standard output."),
    ] = None,
    database_url: DatabaseUrlOption = None,
) -> None:
    """The unit's calibration certificate (or failure report), HTML."""
    from datetime import UTC, datetime

    from db import repository_transaction
    from db.certificates import certificate_inputs
    from station.domain.i18n import LANGUAGES, Language
    from station.domain.laboratory import Laboratory, load_laboratory
    from station.domain.quality.shifts import parse_shifts
    from station.report.html import certificate_page
    from station.report.period import plant_zone

    if language not in LANGUAGES:
        raise InputError(f"--language {language!r} is not one of {', '.join(LANGUAGES)}")
    reader: Language = language  # type: ignore[assignment]  # checked against LANGUAGES
    zone = plant_zone(timezone)
    starts = parse_shifts(shifts)
    laboratory = Laboratory() if config is None else load_laboratory(config)
    with repository_transaction(database_url) as repository:
        found = certificate_inputs(repository, serial, zone, starts)
    if found is None:
        raise InputError(f"no calibration run of serial {serial!r}")
    page = certificate_page(
        found.run,
        found.profile,
        datetime.now(UTC),
        found.gyro_fit,
        found.earlier,
        zone,
        found.golden,
        found.reviews,
        reader,
        laboratory,
    )
    if output is None:
        out.file.write(page)
        out.file.flush()
        return
    try:
        output.write_text(page, encoding="utf-8")
    except OSError as exc:
        raise CalstationError(f"{output}: cannot write the certificate: {exc.strerror}") from None
    err.print(f"certificate written to {output}", markup=False)
