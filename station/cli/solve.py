"""``calstation solve FILE``: calibrate from a file of still-pose means."""

# Light to import: --help and refused arguments read only the signatures below;
# each command imports its work (numpy, SQLAlchemy, the loop, ...) when it runs.

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer
from rich.table import Table

from station.cli.output import out, print_json
from station.domain.constants import STILL_WINDOW_S
from station.domain.errors import InputError
from station.domain.sensor import AXES

if TYPE_CHECKING:
    from station.domain.calibration import Solution, Uncertainty
    from station.domain.calibration.units import DeclaredUnits
    from station.domain.posefile import PoseFile

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
    file: Annotated[
        Path,
        typer.Argument(
            help="CSV with a header holding ax,ay,az, one pose a row; with --stream the raw "
            "samples under t,ax,ay,az,gx,gy,gz."
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
            file,
            model.value,
            as_json=as_json,
            still_window_s=still_window,
            units=stream_units,
            known_turn_deg=known_turn_deg,
        )
        return
    if declared:
        raise InputError(
            "--gyro-units, --time-units, --rate and --known-turn-deg describe a raw stream: "
            "use them with --stream"
        )
    from station.domain.calibration import (
        CalibrationError,
        Uncertainty,
        accelerometer_budget,
        solve,
    )
    from station.domain.calibration.units import DeclaredUnits
    from station.domain.limits import load_profile
    from station.domain.posefile import read_pose_file

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
    budget = accelerometer_budget(solution, poses, spread, pose_file.samples)
    uncertainty = Uncertainty.of_budget(budget)
    if as_json:
        print_json(units.restate(solution.to_dict() | {"uncertainty": uncertainty.to_dict()}))
    else:
        out.print(_table(solution, pose_file, uncertainty, units))


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
