"""``calstation solve FILE``: calibrate from a file of still-pose means."""

# Light to import: --help and refused arguments read only the signatures below;
# each command imports its work (numpy, SQLAlchemy, the loop, ...) when it runs.

from __future__ import annotations

from collections.abc import Sequence
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.table import Table

from station.cli.output import out, print_json
from station.domain.constants import STILL_WINDOW_S
from station.domain.errors import InputError
from station.domain.sensors.sensor import AXES

if TYPE_CHECKING:
    from station.domain.arrays import FloatArray
    from station.domain.calibration import Solution, Uncertainty
    from station.domain.calibration.units import DeclaredUnits
    from station.domain.signals.posefile import PoseFile

#: Decimals the screen shows of an offset or its U, by declared unit (counts: the caller's).
OFFSET_DECIMALS = {"counts": 0, "g": 3, "m/s2": 2}
#: Decimals added for a sensitivity given as a scale factor rather than in counts/g.
SCALE_DECIMALS = 3


class ModelChoice(StrEnum):
    """The calibration models offered on the command line."""

    six = "six"
    nine = "nine"


class AccelUnitsChoice(StrEnum):
    """What the accelerometer's readings are in (a stream's columns, a pose file's means)."""

    counts = "counts"
    g = "g"
    ms2 = "m/s2"


class GyroUnitsChoice(StrEnum):
    """What a stream's gyro columns are in."""

    dps = "dps"
    rads = "rads"


class TimeUnitsChoice(StrEnum):
    """What a stream's time column is in."""

    s = "s"
    ms = "ms"


def solve_command(
    files: Annotated[
        list[Path],
        typer.Argument(
            help="CSV with a header holding ax,ay,az, one pose a row; with --stream the raw "
            "samples under t,ax,ay,az,gx,gy,gz (several: power-on sessions of one unit, "
            "their gyro bias repeatability measured and put in U).",
        ),
    ],
    model: Annotated[
        ModelChoice,
        typer.Option(
            help="six: the paper's eq. 10 (least squares beyond six poses); nine: with cross-axis."
        ),
    ] = ModelChoice.six,
    limits: Annotated[
        Path | None,
        typer.Option("--limits", help="Limits profiles file (default: the shipped profiles)."),
    ] = None,
    profile: Annotated[
        str | None,
        typer.Option("--profile", help="Profile whose fit_residual_counts limits the residuals."),
    ] = None,
    as_json: Annotated[
        bool, typer.Option("--json", help="Print the result as JSON on stdout.")
    ] = False,
    stream: Annotated[
        bool,
        typer.Option(
            "--stream",
            help="FILE is a raw stream: find the still poses, fit the accelerometer, the "
            "gyro bias and the gyro matrix from the moves (docs/calibration.md).",
        ),
    ] = False,
    still_window: Annotated[
        float | None,
        typer.Option(
            help="With --stream: seconds a still window lasts (default: fitted to the "
            f"recording's rests, at most {STILL_WINDOW_S:g} s).",
            min=0.01,
        ),
    ] = None,
    accel_units: Annotated[
        AccelUnitsChoice,
        typer.Option(
            help="The accelerometer's readings in ADC counts, in g or in m/s²; the results "
            "are given in the same unit (docs/calibration.md)."
        ),
    ] = AccelUnitsChoice.counts,
    gyro_units: Annotated[
        GyroUnitsChoice,
        typer.Option(help="With --stream: the gyro columns in deg/s or rad/s."),
    ] = GyroUnitsChoice.dps,
    time_units: Annotated[
        TimeUnitsChoice,
        typer.Option(help="With --stream: the time column in seconds or milliseconds."),
    ] = TimeUnitsChoice.s,
    rate: Annotated[
        float | None,
        typer.Option(
            help="With --stream: the sample rate, samples/s (the time column is then ignored)."
        ),
    ] = None,
    offset_tempco: Annotated[
        float | None,
        typer.Option(
            "--offset-tempco",
            help="The sensor's largest temperature coefficient of its zero g, ± mg/°C "
            "(datasheet; default the putter's KXM52, 2.33): with a temp_c column, the "
            "drift across the poses in U.",
            min=0.0,
            max=100.0,
        ),
    ] = None,
    sensitivity_tempco: Annotated[
        float | None,
        typer.Option(
            "--sensitivity-tempco",
            help="The sensor's largest temperature coefficient of its sensitivity, ± %/°C "
            "(datasheet; default the putter's KXM52, 0.046).",
            min=0.0,
            max=1.0,
        ),
    ] = None,
    cross_axis: Annotated[
        float | None,
        typer.Option(
            "--cross-axis",
            help="The accelerometer's cross-axis sensitivity, ± % (datasheet; default the "
            "putter's KXM52, 2): the six-parameter model's unmodelled coupling in U.",
            min=0.0,
            max=20.0,
        ),
    ] = None,
    gyro_bias_repeatability: Annotated[
        float | None,
        typer.Option(
            "--gyro-bias-repeatability",
            help="With --stream: the gyros' turn-on to turn-on bias repeatability, deg/s "
            "(1 σ, datasheet or measured across sessions), added to the gyro bias's U; "
            "without it U holds this session's mean only, and says so.",
            min=0.0,
            max=100.0,
        ),
    ] = None,
    known_turn_deg: Annotated[
        float | None,
        typer.Option(
            help="With --stream: the recording's whole turns (Ferraris' 360° about each "
            "axis) sweep this many degrees; the gyro matrix fit uses them.",
            min=1.0,
            max=3600.0,
        ),
    ] = None,
) -> None:
    """Compute offsets and sensitivities from still-pose means, in the declared units."""
    declared = (
        gyro_units is not GyroUnitsChoice.dps
        or time_units is not TimeUnitsChoice.s
        or rate is not None
        or known_turn_deg is not None
        or gyro_bias_repeatability is not None
    )
    if stream:
        from station.cli.solve_stream import solve_stream
        from station.domain.gyro.motion.errors import StreamError
        from station.domain.gyro.motion.stream_units import StreamUnits

        try:
            stream_units = StreamUnits(accel_units.value, gyro_units.value, time_units.value, rate)
        except StreamError as exc:
            raise InputError(f"--rate: {exc}") from None
        solve_stream(
            files,
            model.value,
            as_json=as_json,
            still_window_s=still_window,
            units=stream_units,
            known_turn_deg=known_turn_deg,
            tempco=declared_tempco(
                offset_tempco, sensitivity_tempco, stream_units.accelerometer.counts_per_g
            ),
            cross_axis_bound=declared_cross_axis(cross_axis),
            gyro_bias_repeatability_dps=gyro_bias_repeatability,
        )
        return
    if declared:
        raise InputError(
            "--gyro-units, --time-units, --rate, --known-turn-deg and "
            "--gyro-bias-repeatability describe a raw stream: use them with --stream"
        )
    if len(files) > 1:
        raise InputError(
            f"{len(files)} files: several files are power-on sessions of one unit's raw "
            "recording: use them with --stream, or give one pose file"
        )
    file = files[0]
    from station.domain.calibration import (
        CalibrationError,
        Uncertainty,
        accelerometer_budget,
        solve,
    )
    from station.domain.calibration.units import DeclaredUnits
    from station.domain.product.limits import load_profile
    from station.domain.signals.posefile import read_pose_file

    units = DeclaredUnits(accel_units.value)
    if units.accel != "counts" and (limits is not None or profile is not None):
        raise InputError(
            f"--limits/--profile: a profile's limits are in its product's ADC counts, the "
            f"poses in {units.accel}: no limit applies to them; leave out --limits and --profile"
        )
    max_residual = load_profile(limits, profile).max_residual_counts
    pose_file = read_pose_file(file)
    poses = units.to_counts(pose_file.poses)
    spread = None if pose_file.spread is None else units.spread_to_counts(pose_file.spread)
    try:
        solution = solve(poses, model.value, max_residual_counts=max_residual)
    except CalibrationError as exc:
        raise InputError(f"{pose_file.where(exc.pose)}: {exc}") from None
    tempco = declared_tempco(offset_tempco, sensitivity_tempco, units.counts_per_g)
    budget = accelerometer_budget(
        solution,
        poses,
        spread,
        pose_file.samples,
        temperatures=pose_file.temperatures,
        tempco=tempco,
        cross_axis_bound=declared_cross_axis(cross_axis),
    )
    uncertainty = Uncertainty.of_budget(budget)
    disturbed = [
        {"pose": pose + 1, "spread_over_noise": ratio} for pose, ratio in budget.disturbed.items()
    ]
    temperature = temperature_summary(pose_file.temperatures)
    if as_json:
        print_json(
            units.restate(
                solution.to_dict()
                | {
                    "uncertainty": uncertainty.to_dict(),
                    "disturbed_poses": disturbed,
                    "temperature_c": temperature,
                    "excluded_influences": excluded(budget.excluded_influences),
                }
            )
        )
    else:
        table = _table(solution, pose_file, uncertainty, units)
        notes = [
            f"DISTURBED pose {pose + 1} ({pose_file.where(pose)}): its spread is {ratio:.3g}× "
            "the poses' noise (moved while taken?): its excess counted in U undivided by its "
            "sample count"
            for pose, ratio in budget.disturbed.items()
        ]
        table.caption = "\n".join(
            [*notes, str(table.caption), *influence_lines(temperature, budget.excluded_influences)]
        )
        out.print(table)


def declared_tempco(
    offset_mg_per_c: float | None, sensitivity_percent_per_c: float | None, counts_per_g: float
) -> tuple[float, float]:
    """The temperature coefficients' half-widths the budget takes (counts/°C, /°C): those
    declared (mg/°C, %/°C), else the putter's KXM52's."""
    from station.domain.calibration.uncertainty import (
        OFFSET_TEMPCO_BOUND,
        SENSITIVITY_TEMPCO_BOUND,
    )

    return (
        OFFSET_TEMPCO_BOUND if offset_mg_per_c is None else offset_mg_per_c / 1000 * counts_per_g,
        SENSITIVITY_TEMPCO_BOUND
        if sensitivity_percent_per_c is None
        else sensitivity_percent_per_c / 100,
    )


def declared_cross_axis(percent: float | None) -> float:
    """The budget's unmodelled coupling (a fraction): declared in %, else the KXM52's."""
    from station.domain.calibration.uncertainty import CROSS_AXIS_BOUND

    return CROSS_AXIS_BOUND if percent is None else percent / 100


def temperature_summary(temperatures: FloatArray | None) -> dict[str, float] | None:
    """The JSON's ``temperature_c``: the poses' mean temperature (the results hold there)
    and their span (the drift U holds), °C; None without temperatures."""
    if temperatures is None:
        return None
    return {
        "mean": float(temperatures.mean()),
        "span": float(temperatures.max() - temperatures.min()),
    }


def excluded(names: Sequence[str]) -> list[dict[str, str]]:
    """The JSON's ``excluded_influences``: each influence left out of U and why."""
    from station.domain.calibration.uncertainty import EXCLUDED_WHY

    return [{"influence": name, "why": EXCLUDED_WHY[name]} for name in names]


def influence_lines(temperature: dict[str, float] | None, names: Sequence[str]) -> list[str]:
    """The screen's lines on the temperature and on what U leaves out."""
    lines = (
        []
        if temperature is None
        else [
            f"temperature: poses at {temperature['mean']:.2f} °C mean (the results hold there), "
            f"span {temperature['span']:.2f} °C, its drift in U"
        ]
    )
    return lines + [f"NOT IN U: {e['influence']}: {e['why']}" for e in excluded(names)]


def unit_headers(units: DeclaredUnits) -> tuple[str, str]:
    """The offset's and the sensitivity's column titles in the declared units."""
    sensitivity = "counts/g" if units.accel == "counts" else "scale factor"
    return f"offset ({units.accel})", f"sensitivity ({sensitivity})"


def unit_decimals(units: DeclaredUnits, counts_decimals: int) -> tuple[int, int]:
    """Decimals of an offset and of a sensitivity, ``counts_decimals`` for counts."""
    offset = counts_decimals + OFFSET_DECIMALS[units.accel]
    scale = 0 if units.accel == "counts" else SCALE_DECIMALS
    return offset, counts_decimals + scale


def _table(
    solution: Solution, pose_file: PoseFile, uncertainty: Uncertainty, units: DeclaredUnits
) -> Table:
    from station.domain.calibration import MIN_DOF_SHOWN, SENSITIVITY_CONVENTION

    cal, q = solution.calibration, solution.quality
    se = solution.standard_errors
    shown = se is not None and se.dof >= MIN_DOF_SHOWN
    table = Table(
        title=f"{pose_file.path}: {solution.poses} poses, {cal.model}-parameter model "
        f"({solution.method})"
    )
    offset_header, sensitivity_header = unit_headers(units)
    table.add_column("axis")
    table.add_column(offset_header, justify="right")
    table.add_column(sensitivity_header, justify="right")
    table.add_column(f"U offset (k = {uncertainty.k:g})", justify="right")
    table.add_column(f"U sensitivity (k = {uncertainty.k:g})", justify="right")
    do, ds = unit_decimals(units, 4)
    offset, sensitivity = units.offset(cal.offset), units.sensitivity(cal.sensitivity)
    u_off = None if uncertainty.offset is None else units.spread(uncertainty.offset)
    u_sens = None if uncertainty.sensitivity is None else units.sensitivity(uncertainty.sensitivity)
    for i, axis in enumerate(AXES):
        off = f"{offset[i]:.{do}f}"
        sens = f"{sensitivity[i]:.{ds}f}"
        if shown and se is not None:
            off += f" ± {units.spread(se.offset)[i]:.{do}f}"
            sens += f" ± {units.sensitivity(se.sensitivity)[i]:.{ds}f}"
        table.add_row(
            axis,
            off,
            sens,
            "—" if u_off is None else f"± {u_off[i]:.{do}f}",
            "—" if u_sens is None else f"± {u_sens[i]:.{ds}f}",
        )
    lines = [
        f"residual |g|−1: rms {q.residual_rms_mg:.3f} mg, max {q.residual_max_mg:.3f} mg",
        f"condition number {q.condition_number:.3g}, coverage {q.coverage:.3f}, "
        f"closest poses {q.closest_pair[0] + 1} and {q.closest_pair[1] + 1}, "
        f"{q.min_angle_deg:.1f}°",
    ]
    noted = (
        ""
        if pose_file.spread is not None
        else ("; the file gives no sx,sy,sz,n: each pose's noise taken as the sensor's")
    )
    if pose_file.spread is None and units.accel != "counts":
        from station.domain.calibration.uncertainty import DEFAULT_SAMPLE_NOISE_COUNTS

        assumed = units.residual(DEFAULT_SAMPLE_NOISE_COUNTS)
        noted += f" (the putter's, {assumed:.3g} {units.accel} a sample)"
    lines.append(
        f"U: expanded uncertainty, k = {uncertainty.k:g} (GUM budget, docs/calibration.md){noted}"
    )
    if se is not None:
        lines.append(
            f"± 1-σ standard errors, {se.dof} degrees of freedom"
            if shown
            else f"no ± shown: {se.dof} degree(s) of freedom, too few to estimate the noise"
        )
    if q.studentised_max_counts is not None:
        worst = units.residual(q.studentised_max_counts)
        limit = solution.residual_limit_counts
        shown_limit = "none" if limit is None else f"{units.residual(limit):.3g}"
        lines.append(
            f"studentised residual max {worst:.3g} {units.accel} "
            f"(limit {shown_limit}, {solution.checked_with}-parameter check)"
        )
    if solution.k is not None:
        lines.insert(0, f"k1 = {solution.k[0]:.6f}, k2 = {solution.k[1]:.6f}")
    if cal.model == "nine":
        lines.append(f"sensitivity = {SENSITIVITY_CONVENTION['nine']}")
        maps = (
            "counts → g" if units.accel == "counts" else f"{units.accel} − offset → {units.accel}"
        )
        lines.append(
            f"matrix ({maps}): "
            + "; ".join(" ".join(f"{v:+.6e}" for v in row) for row in units.matrix(cal.matrix))
        )
    if q.near_duplicates:
        lines.insert(
            0,
            f"NOTE near-duplicates: {q.near_duplicates} poses lie within 10° of another "
            "(they add little; least squares needs no rule against them)",
        )
    for pose in solution.excluded:
        off_by = units.residual(float(q.pose_g[pose] - 1) * units.counts_per_g)
        lines.insert(
            0,
            f"EXCLUDED pose {pose + 1} ({pose_file.where(pose)}): inconsistent with the others, "
            f"{off_by:+.{unit_decimals(units, 1)[0]}f} {units.accel} off; fit redone without it",
        )
    table.caption = "\n".join(lines)
    return table
