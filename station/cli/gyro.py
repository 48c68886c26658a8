"""``calstation gyro``: fit the g-sensitivity error model, simulate the centrifuge test.

matplotlib is imported inside ``fit --plot`` only, so that ``fit`` without a plot does
not pay for it either.
"""

# Light to import: --help and refused arguments read only the signatures below;
# each command imports its work (numpy, SQLAlchemy, the loop, ...) when it runs.

from __future__ import annotations

import math
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from pydantic import ValidationError
from rich.table import Table

from station.cli.output import err, out, print_json
from station.domain.constants import DEFAULT_ALPHA, DEFAULT_SENSE_AXES, PAPER_PPM_PER_G
from station.domain.errors import InputError
from station.domain.sensors.sensor import AXES

if TYPE_CHECKING:
    from station.domain.gyro.fit import GyroFitReport
    from station.domain.gyro.log import GyroLog

app = typer.Typer(
    help="Gyros: fit the g-sensitivity error model, simulate the centrifuge test.",
    no_args_is_help=True,
)


def _triple(option: str, text: str) -> tuple[float, float, float]:
    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != 3 or not all(map(math.isfinite, values)):
        raise InputError(f"{option}: expected three numbers separated by commas, got {text!r}")
    return values[0], values[1], values[2]


def _axes(option: str, text: str) -> tuple[int, int, int]:
    parts = [p.strip().lower() for p in text.split(",")]
    if len(parts) != 3 or any(p not in AXES for p in parts):
        raise InputError(f"{option}: expected three of x, y, z separated by commas, got {text!r}")
    i, j, k = (AXES.index(p) for p in parts)
    return i, j, k


def _cell(value: float | None, fmt: str) -> str:
    return "—" if value is None else format(value, fmt)


def _estimate(value: float | None, error: float | None, fmt: str) -> str:
    if value is None:
        return "—"
    return format(value, fmt) + ("" if error is None else " ± " + format(error, ".2g"))


def _print_report(report: GyroFitReport) -> None:
    se = report.standard_errors
    table = Table(title=f"Gyro error model ({report.dwells} dwells)")
    for column in ("gyro", "bias deg/s", "sense axis", "residual rms deg/s"):
        table.add_column(column)
    for i, axis in enumerate(AXES):
        table.add_row(
            axis,
            _estimate(report.bias_dps[i], se.bias_dps[i], ".5f"),
            report.sense_axis[i] or "—",
            f"{report.residual_rms_dps[i]:.5f}",
        )
    out.print(table)
    matrices = (
        (
            "S, scale factor and misalignment (row gyro, column rate)",
            report.scale_matrix,
            se.scale_matrix,
            ".6f",
        ),
        (
            "B, bias-form g-sensitivity, deg/s/g",
            report.bias_g_sensitivity_dps_per_g,
            se.bias_g_sensitivity_dps_per_g,
            ".5f",
        ),
        (
            "N, scale-factor-form g-sensitivity, ppm/g",
            report.g_sensitivity_ppm_per_g,
            se.g_sensitivity_ppm_per_g,
            ".1f",
        ),
    )
    for title, values, errors, fmt in matrices:
        table = Table(title=title)
        for column in ("gyro", *AXES):
            table.add_column(column, justify="right")
        for i, axis in enumerate(AXES):
            table.add_row(
                axis, *(_estimate(v, e, fmt) for v, e in zip(values[i], errors[i], strict=True))
            )
        out.print(table)
    for comparison in report.comparison:
        tests = ", ".join(
            f"{t.full} vs {t.reduced}: p={_cell(t.p_value, '.3g')}" for t in comparison.tests
        )
        verdict = comparison.verdict or f"undecided ({comparison.reason})"
        out.print(
            f"gyro {comparison.axis}: form {verdict}; BIC prefers "
            f"{comparison.preferred_by_bic or '—'}; {tests}"
        )
    for term in report.unestimable:
        out.print(f"not estimable: {term.term}: {term.reason}", markup=False)


@app.command()
def fit(
    log_file: Annotated[
        Path, typer.Argument(metavar="LOG.csv", help="Rate-table or centrifuge log.")
    ],
    json_output: Annotated[bool, typer.Option("--json", help="Print the result as JSON.")] = False,
    plot: Annotated[
        Path | None, typer.Option(metavar="FILE", help="Write the scale-factor plot (.png, .svg).")
    ] = None,
    alpha: Annotated[float, typer.Option(help="Significance level of the tests.")] = DEFAULT_ALPHA,
    store: Annotated[
        str | None,
        typer.Option(
            metavar="SERIAL",
            help="Store the fit as this unit's gyro calibration in the results database.",
        ),
    ] = None,
) -> None:
    """Fit bias, scale factor, misalignment and both forms of g-sensitivity to a log."""

    if not 0.0 < alpha < 1.0:
        raise InputError(f"--alpha: must lie between 0 and 1, got {alpha:g}")
    from station.domain.gyro.fit import fit_log
    from station.domain.gyro.log import read_log

    log = read_log(log_file)
    try:
        report = fit_log(log, alpha=alpha)
    except InputError as exc:
        raise InputError(f"{log_file}: {exc}") from None
    if plot is not None:
        from station.report.gyro_plot import plot_g_sensitivity, sense_axes_of

        model = report.error_model()
        sense = sense_axes_of(report, model)
        plot_g_sensitivity(log, model, sense, plot)
    if store is not None:
        _store_fit(store, log_file, report, log)
    if json_output:
        print_json(report.to_dict())
    else:
        _print_report(report)


@app.command()
def check(
    log_file: Annotated[
        Path, typer.Argument(metavar="LOG.csv", help="Rate-table or centrifuge log.")
    ],
    json_output: Annotated[
        bool, typer.Option("--json", help="Print the findings as JSON.")
    ] = False,
) -> None:
    """Check that a log can separate the model's terms and tell bias from scale-factor form.

    Prints the findings; exits with status 2 when the form question cannot be answered.
    """
    from station.domain.gyro.identifiability import check_identifiability
    from station.domain.gyro.log import read_log

    log = read_log(log_file)
    try:
        report = check_identifiability(log)
    except InputError as exc:
        raise InputError(f"{log_file}: {exc}") from None
    if json_output:
        print_json(report.model_dump(mode="json"))
    else:
        for axis in report.axes:
            condition = _cell(axis.condition_number, ".3g")
            out.print(
                f"gyro {axis.axis}: {axis.dwells} dwells, rank {axis.rank} of "
                f"{axis.excited_columns} excited terms, condition number {condition}"
            )
            for status in axis.terms:
                if not status.estimable:
                    out.print(f"  not estimable: {status.term}: {status.reason}", markup=False)
            for caveat in axis.caveats:
                out.print(f"  caveat: {caveat}", markup=False)
    report.require_form_question()


@app.command("simulate-centrifuge")
def simulate_centrifuge(
    out_file: Annotated[
        Path | None, typer.Option("--out", metavar="LOG.csv", help="Output file (default: stdout).")
    ] = None,
    seed: Annotated[int | None, typer.Option(help="Random seed, for a repeatable log.")] = None,
    ppm: Annotated[
        str, typer.Option(help="Scale-factor g-sensitivity of gyro x,y,z on its sense axis, ppm/g.")
    ] = ",".join(f"{v:g}" for v in PAPER_PPM_PER_G),
    bias_form: Annotated[
        str, typer.Option(help="Bias-form g-sensitivity of gyro x,y,z on its sense axis, deg/s/g.")
    ] = "0,0,0",
    sense_axes: Annotated[str, typer.Option(help="Sense axis of gyro x,y,z.")] = ",".join(
        AXES[j] for j in DEFAULT_SENSE_AXES
    ),
    arm_m: Annotated[float, typer.Option(help="Centrifuge arm, m.")] = 3.0,
    g_max: Annotated[float, typer.Option(help="Largest radial acceleration, g.")] = 30.0,
    g_step: Annotated[float, typer.Option(help="Acceleration step, g.")] = 3.0,
    noise_dps: Annotated[float, typer.Option(help="Gyro noise per row, deg/s.")] = 0.01,
    acc_noise_g: Annotated[float, typer.Option(help="Accelerometer noise per row, g.")] = 0.001,
    samples_per_dwell: Annotated[
        int, typer.Option(help="Rows per dwell (>1 adds a segment column).")
    ] = 1,
    single_mount: Annotated[
        bool, typer.Option(help="One mount only (x up, arm along y), no rate table.")
    ] = False,
) -> None:
    """Simulate the paper's centrifuge test plus rate-table steps, from a known truth."""
    for name, value in (("--arm-m", arm_m), ("--g-max", g_max), ("--g-step", g_step)):
        if not value > 0:
            raise InputError(f"{name}: must be positive, got {value:g}")
    if noise_dps < 0 or acc_noise_g < 0:
        raise InputError("--noise-dps, --acc-noise-g: must not be negative")
    if samples_per_dwell < 1:
        raise InputError(f"--samples-per-dwell: must be at least 1, got {samples_per_dwell}")
    from station.domain.gyro.log import write_log
    from station.domain.gyro.simulate import CentrifugePlan, Mount, Noise, paper_truth, simulate_log

    truth = paper_truth(
        ppm_per_g=_triple("--ppm", ppm),
        sense_axes=_axes("--sense-axes", sense_axes),
        bias_form_dps_per_g=_triple("--bias-form", bias_form),
    )
    plan = CentrifugePlan(arm_m=arm_m, g_max=g_max, g_step=g_step)
    if single_mount:
        plan = CentrifugePlan(
            arm_m=arm_m, g_max=g_max, g_step=g_step, mounts=(Mount(0, 1, 1, 1),), rate_table=False
        )
    log, segments = simulate_log(
        truth, plan, Noise(gyro_dps=noise_dps, acc_g=acc_noise_g), samples_per_dwell, seed
    )
    if out_file is None:
        write_log(out.file, log, segments)
        return
    try:
        with out_file.open("w", newline="", encoding="utf-8") as handle:
            write_log(handle, log, segments)
    except OSError as exc:
        raise InputError(f"{out_file}: cannot write ({exc.strerror})") from None
    err.print(f"wrote {len(log)} rows to {out_file}", markup=False)


def _store_fit(serial: str, log_file: Path, report: GyroFitReport, log: GyroLog) -> None:
    """Keep ``report`` as the unit's gyro calibration (``GET /api/v1/units/SERIAL/gyro``)."""
    from db import repository_transaction
    from station.domain.gyro.log import GyroDwells
    from station.domain.record.records import GyroFitRecord

    try:
        record = GyroFitRecord(
            serial=serial,
            fitted_at=datetime.now(UTC),
            source=log_file.name,
            report=report,
            dwells=GyroDwells.of(log),
        )
    except ValidationError:
        raise InputError(f"--store: {serial!r} is not a serial number") from None
    with repository_transaction() as repository:
        repository.add_gyro_fit(record)
    err.print(f"gyro fit stored for {serial}", markup=False)
