"""``calstation run`` (the operator station) and ``calstation demo`` (the same, scripted)."""

# Light to import: --help and refused arguments read only the signatures below;
# each command imports its work (numpy, SQLAlchemy, the loop, ...) when it runs.

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from station.cli.main import EXIT_INTERRUPTED
from station.cli.output import err, out, print_json, screen_console
from station.domain.constants import MAX_SLOTS
from station.domain.errors import CalstationError

if TYPE_CHECKING:
    from station.domain.product.limits import LimitsProfile
    from station.domain.record.records import RunRecord
    from station.loop.app import StationApp
    from station.loop.config import StationConfig
    from station.loop.demo import DemoUnit
    from station.loop.fixture.app import FixtureApp
    from station.loop.keyboard import KeySource
    from station.results.storage import RunStore

ConfigOption = Annotated[
    Path | None, typer.Option("--config", help="Station configuration (TOML).")
]
StationOption = Annotated[str | None, typer.Option("--station", help="Station id.")]
OperatorOption = Annotated[str | None, typer.Option("--operator", help="Operator id.")]
LotOption = Annotated[
    str | None, typer.Option("--lot", help="Production lot of the units (recorded on each run).")
]
LanguageOption = Annotated[
    str | None,
    typer.Option("--language", help="The operator's language: en, ko or zh.", show_default=False),
]
PartNumberOption = Annotated[
    str | None,
    typer.Option(
        "--part-number",
        help="The product calibrated (its sensor, limits and plan; default DIXX-A12).",
    ),
]
LimitsOption = Annotated[Path | None, typer.Option("--limits", help="Limits profiles file (TOML).")]
ProfileOption = Annotated[str | None, typer.Option("--profile", help="Limits profile name.")]
ServerOption = Annotated[
    str | None, typer.Option("--server", help="Results server URL (instead of the database).")
]
KeyOption = Annotated[
    str | None, typer.Option("--api-key", help="The station's API key for --server.")
]


def _store_opener(config: StationConfig) -> Any:
    from station.results.storage import DatabaseStore, HttpStore

    def open_store() -> RunStore:
        if config.server_url:
            return HttpStore(config.server_url, config.api_key or "", station_id=config.station_id)
        return DatabaseStore(config.database_url)

    return open_store


def _station(
    config: StationConfig,
    profile: LimitsProfile,
    keys: KeySource,
    console: Any,
    units: int | None,
    probe_port: bool = True,
    speed: float = 1.0,
) -> StationApp | FixtureApp:
    """The one-port station, or the fixture's when several slots are configured;
    ``speed``: the virtual putters' clock (the demo's), which the loop's passes follow, so
    that a pass comes every quarter second of the units' own time, as on the line."""
    from station.loop.app import StationApp
    from station.loop.fixture.app import FixtureApp
    from station.loop.live_loop import TICK_S

    front_end = FixtureApp if config.slots else StationApp
    return front_end(
        config=config,
        profile=profile,
        open_store=_store_opener(config),
        keys=keys,
        console=console,
        units=units,
        probe_ports=probe_port,
        tick_s=TICK_S / speed,
    )


def _serve(app: StationApp | FixtureApp) -> str | None:
    """Serve until done; stopped by Ctrl-C, the line that says what it left (the journals
    stay for the next start)."""
    try:
        app.serve()
    except KeyboardInterrupt:
        return app.stopped_line()
    return None


def _stopped(app: StationApp | FixtureApp, interrupted: str | None = None) -> None:
    """A station stopped by Ctrl-C says ``interrupted`` (what it left) on standard error;
    one that stopped holding runs only in memory says where they went (the runs themselves
    on standard error when no directory took them) and exits with status 2; Ctrl-C, 130."""
    if interrupted is not None:
        err.print(interrupted, markup=False, highlight=False, soft_wrap=True)
    rescued = app.rescued
    if rescued is not None:
        for line in rescued.lines:
            err.print(line, markup=False, highlight=False, soft_wrap=True)
        raise CalstationError(rescued.sentence)
    if interrupted is not None:
        raise SystemExit(EXIT_INTERRUPTED)


def run_command(
    ports: Annotated[
        list[str] | None,
        typer.Option(
            "--port",
            help="Putter port: /dev/ttyUSB0, a pty, socket://host:port; "
            f"repeat it for a fixture's slots (at most {MAX_SLOTS}).",
        ),
    ] = None,
    config_file: ConfigOption = None,
    station: StationOption = None,
    operator: OperatorOption = None,
    lot: LotOption = None,
    part_number: PartNumberOption = None,
    language: LanguageOption = None,
    limits: LimitsOption = None,
    profile: ProfileOption = None,
    server: ServerOption = None,
    api_key: KeyOption = None,
    units: Annotated[int | None, typer.Option(help="Stop after this many units.")] = None,
) -> None:
    """The operator station: scan a unit, take its poses, judge it, store it."""
    from station.domain.product.limits import load_profile
    from station.loop.keyboard import TerminalKeys
    from station.loop.startup import check_port, prepare_data_dir

    config = _load_config(
        config_file,
        {
            "slots": ports or None,
            "station_id": station,
            "operator_id": operator,
            "lot": lot,
            "part_number": part_number,
            "language": language,
            "limits_file": limits,
            "limits_profile": profile,
            "server_url": server,
            "api_key": api_key,
        },
    )
    limits_profile = load_profile(config.limits_file, config.limits_profile)
    prepare_data_dir(config.data_dir)
    if not config.slots:
        check_port(config.port)
    with TerminalKeys() as keys:
        app = _station(config, limits_profile, keys, screen_console(), units)
        stopped = _serve(app)
    _stopped(app, stopped)


def demo_command(
    units: Annotated[int, typer.Option(min=1, help="Units to calibrate.")] = 3,
    as_json: Annotated[
        bool, typer.Option("--json", help="Print one JSON list of the units on stdout.")
    ] = False,
    speed: Annotated[
        float, typer.Option(min=0.1, help="Virtual clock speed (× real time).")
    ] = 10.0,
    seed: Annotated[int, typer.Option(help="Seed of the virtual units.")] = 1,
    profile: Annotated[
        str | None,
        typer.Option(
            "--profile",
            help="Limits profile, with its run plan if one is shipped: whole-unit "
            "calibrates the gyro matrix too (12 poses).",
        ),
    ] = None,
    slots: Annotated[
        int,
        typer.Option(min=1, max=MAX_SLOTS, help="Slots of the fixture: units calibrated together."),
    ] = 1,
    pull_cables: Annotated[
        float,
        typer.Option(
            min=0.0,
            max=1.0,
            help="The operator pulls a unit's cable at a move with this chance, and plugs "
            "it back a moment later: the station carries on.",
        ),
    ] = 0.0,
    config_file: ConfigOption = None,
    station: StationOption = None,
    operator: OperatorOption = None,
    lot: LotOption = None,
    part_number: PartNumberOption = None,
    language: LanguageOption = None,
) -> None:
    """The station on virtual putters, with a scripted operator: the main job's demo."""
    from station.domain.i18n import tr, trn
    from station.domain.product.limits import load_profile
    from station.loop.demo import CablePuller, ScriptedOperator
    from station.loop.fixture.demo import FixtureOperator
    from station.loop.startup import prepare_data_dir

    config = _load_config(
        config_file,
        {
            "station_id": station,
            "operator_id": operator,
            "lot": lot,
            "limits_profile": profile,
            "part_number": part_number,
            "language": language,
        },
        # The demo's own ids, where neither the file, the environment nor a flag names one.
        defaults={"station_id": "demo-station", "operator_id": "demo-operator", "lot": "demo-lot"},
    )
    sensor = config.product.sensor
    prepare_data_dir(config.data_dir)
    first = _first_new_unit(config, seed)
    cables = CablePuller(rate=pull_cables, seed=seed)
    demo_dir = config.data_dir.expanduser() / "demo"
    operator_script: ScriptedOperator | FixtureOperator
    if slots == 1:
        port = demo_dir / "putter"
        config = config.model_copy(update={"port": str(port), "slots": ()})
        operator_script = ScriptedOperator(
            units=units,
            port=port,
            seed=seed,
            speed=speed,
            first=first,
            cables=cables,
            sensor=sensor,
        )
        where = tr("each plugged into {port} in turn and moved through the poses", port=port)
    else:
        ports = [demo_dir / f"putter-slot{n}" for n in range(1, slots + 1)]
        config = config.model_copy(update={"port": None, "slots": tuple(map(str, ports))})
        operator_script = FixtureOperator(
            units=units,
            ports=ports,
            seed=seed,
            speed=speed,
            first=first,
            cables=cables,
            sensor=sensor,
        )
        where = tr(
            "{slots} at a time in a fixture ({ports}), turned through the poses",
            slots=slots,
            ports=f"{demo_dir}/putter-slotN",
        )
    console = screen_console(stderr=as_json or not out.is_terminal)
    limits = load_profile(config.limits_file, config.limits_profile)
    app = _station(config, limits, operator_script, console, units, probe_port=False, speed=speed)
    operator_script.station = app
    console.print(
        trn(
            "demo: {count} virtual putter, {where} by a scripted operator, at {speed}× real time",
            "demo: {count} virtual putters, {where} by a scripted operator, at {speed}× real time",
            units,
            where=where,
            speed=f"{speed:g}",
        ),
        markup=False,
        highlight=False,
        soft_wrap=not console.is_terminal,  # a terminal's lines wrap between words
    )
    try:
        stopped = _serve(app)
    finally:
        operator_script.close()
    records = app.records
    if stopped is None:
        _demo_summary(records, operator_script.done, as_json)
    _stopped(app, stopped)
    if not records:
        why = app.last_note or tr("no unit got through its scan")
        raise CalstationError(tr("demo: no unit was calibrated: {why}", why=why))
    if not as_json:
        backlog = app.results.outbox.count()
        out.print(
            trn(
                "{count} unit calibrated; outbox {backlog}; database {database}",
                "{count} units calibrated; outbox {backlog}; database {database}",
                len(records),
                backlog=backlog,
                database=config.database_url or config.data_dir,
            )
        )


def _load_config(
    config_file: Path | None, overrides: dict[str, Any], defaults: dict[str, Any] | None = None
) -> StationConfig:
    """The station's configuration (:func:`station.loop.config.load_config`, for ``run``
    and ``demo`` alike); its language is the operator's from here on, so the refusals that
    follow are in it too."""
    from station.domain.i18n import set_language
    from station.loop.config import load_config

    config = load_config(config_file, overrides, defaults)
    set_language(config.language)
    return config


def _first_new_unit(config: StationConfig, seed: int) -> int:
    """The number of the demo's first unit: after every demo unit of ``seed`` the results
    database or the outbox already holds, so that a demo run again calibrates new units
    (a unit calibrated again and again would use up its retest limit)."""
    from sqlalchemy.exc import SQLAlchemyError

    from db import repository_transaction
    from station.loop.demo import demo_serial
    from station.results.outbox import Outbox
    from station.results.outbox_files import summarise

    prefix = demo_serial(seed, 0)[:-3]
    known = {s.serial for s in map(summarise, Outbox(config.outbox_dir).pending()) if s.serial}
    if not config.server_url:
        try:
            with repository_transaction(config.database_url) as repository:
                known.update(repository.serials(prefix))
        except (CalstationError, SQLAlchemyError):
            pass  # the store is out of reach: the outbox is what is known
    numbers = [int(s[len(prefix) :]) for s in known if re.fullmatch(rf"{prefix}\d{{3}}", s)]
    return max(numbers, default=0) + 1


def _demo_summary(records: list[RunRecord], done: list[DemoUnit], as_json: bool) -> None:
    """Each unit's verdict, estimate and truth, as one JSON list (with ``--json``)."""
    if not as_json:
        return
    by_serial = {u.serial: u for u in done}
    summary = []
    for record in records:
        unit = by_serial[record.serial]
        estimate: dict[str, Any] | None = None
        if record.coefficients is not None:
            c = record.coefficients
            estimate = {"offset": c.offset.model_dump(), "sensitivity": c.sensitivity.model_dump()}
            if record.gyro_matrix is not None:
                estimate["gyro_matrix"] = record.gyro_matrix.matrix
        summary.append(
            {
                "serial": record.serial,
                "verdict": record.verdict,
                "run_id": str(record.run_id),
                "truth": unit.truth(),
                "estimate": estimate,
                "failures": [f.model_dump(mode="json") for f in record.failures],
            }
        )
    print_json(summary)
