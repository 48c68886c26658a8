"""``calstation run`` (the operator station) and ``calstation demo`` (the same, scripted)."""

from pathlib import Path
from typing import Annotated, Any

import typer

from station.app import StationApp
from station.cli.output import err, out, print_json
from station.config import StationConfig, load_config
from station.demo import ScriptedOperator
from station.keys import TerminalKeys
from station.limits import load_profile
from station.startup import check_port, prepare_data_dir
from station.storage import DatabaseStore, HttpStore, RunStore

ConfigOption = Annotated[
    Path | None, typer.Option("--config", help="Station configuration (TOML).")
]
StationOption = Annotated[str | None, typer.Option("--station", help="Station id.")]
OperatorOption = Annotated[str | None, typer.Option("--operator", help="Operator id.")]
LotOption = Annotated[
    str | None, typer.Option("--lot", help="Production lot of the units (recorded on each run).")
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
    def open_store() -> RunStore:
        if config.server_url:
            return HttpStore(config.server_url, config.api_key or "")
        return DatabaseStore(config.database_url)

    return open_store


def run_command(
    port: Annotated[
        str | None,
        typer.Option("--port", help="Putter port: /dev/ttyUSB0, a pty, socket://host:port."),
    ] = None,
    config_file: ConfigOption = None,
    station: StationOption = None,
    operator: OperatorOption = None,
    lot: LotOption = None,
    limits: LimitsOption = None,
    profile: ProfileOption = None,
    server: ServerOption = None,
    api_key: KeyOption = None,
    units: Annotated[int | None, typer.Option(help="Stop after this many units.")] = None,
) -> None:
    """The operator station: scan a unit, take its poses, judge it, store it."""
    config = load_config(
        config_file,
        {
            "port": port,
            "station_id": station,
            "operator_id": operator,
            "lot": lot,
            "limits_file": limits,
            "limits_profile": profile,
            "server_url": server,
            "api_key": api_key,
        },
    )
    limits_profile = load_profile(config.limits_file, config.limits_profile)
    prepare_data_dir(config.data_dir)
    check_port(config.port)
    with TerminalKeys() as keys:
        app = StationApp(
            config=config,
            profile=limits_profile,
            open_store=_store_opener(config),
            keys=keys,
            console=out,
            units=units,
        )
        app.serve()


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
    config_file: ConfigOption = None,
    station: StationOption = None,
    operator: OperatorOption = None,
    lot: LotOption = None,
) -> None:
    """The station on virtual putters, with a scripted operator: the main job's demo."""
    config = load_config(
        config_file,
        {
            "station_id": station or "demo-station",
            "operator_id": operator or "demo-operator",
            "lot": lot or "demo-lot",
            "limits_profile": profile,
        },
    )
    prepare_data_dir(config.data_dir)
    port = config.data_dir.expanduser() / "demo" / "putter"
    config = config.model_copy(update={"port": str(port)})
    operator_script = ScriptedOperator(units=units, port=port, seed=seed, speed=speed)
    console = err if as_json or not out.is_terminal else out
    app = StationApp(
        config=config,
        profile=load_profile(config.limits_file, config.limits_profile),
        open_store=_store_opener(config),
        keys=operator_script,
        console=console,
        units=units,
        probe_port=False,
    )
    operator_script.station = app
    console.print(
        f"demo: {units} virtual putter{'s' * (units > 1)}, each plugged into {port} in turn and "
        f"moved through the poses by a scripted operator, at {speed:g}× real time",
        markup=False,
        highlight=False,
    )
    try:
        records = app.serve()
    finally:
        operator_script.close()
    by_serial = {u.serial: u for u in operator_script.done}
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
    if as_json:
        print_json(summary)
    else:
        backlog = app.results.outbox.count()
        where = config.database_url or config.data_dir
        out.print(f"{len(records)} units calibrated; outbox {backlog}; database {where}")
