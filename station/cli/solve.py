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
    from station.domain.posefile import PoseFile


class ModelChoice(StrEnum):
    """The calibration models offered on the command line."""

    six = "six"
    nine = "nine"


class AccelUnitsChoice(StrEnum):
    """What a stream's accelerometer columns are in."""

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
        float,
        typer.Option(help="With --stream: seconds a still window lasts.", min=0.01),
    ] = STILL_WINDOW_S,
    accel_units: Annotated[
        AccelUnitsChoice,
        typer.Option(
            help="With --stream: the accelerometer columns in ADC counts (zero 2048, 819.2 "
            "counts/g), in g or in m/s²."
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
    """Compute offsets and sensitivities from still-pose means (ADC counts)."""
    declared = (
        accel_units is not AccelUnitsChoice.counts
        or gyro_units is not GyroUnitsChoice.dps
        or time_units is not TimeUnitsChoice.s
        or rate is not None
        or known_turn_deg is not None
    )
    if stream:
        from station.cli.solve_stream import solve_stream
        from station.domain.gyro.motion.errors import StreamError
        from station.domain.gyro.motion.stream_units import StreamUnits

        try:
            units = StreamUnits(accel_units.value, gyro_units.value, time_units.value, rate)
        except StreamError as exc:
            raise InputError(f"--rate: {exc}") from None
        solve_stream(
            file,
            model.value,
            as_json=as_json,
            still_window_s=still_window,
            units=units,
            known_turn_deg=known_turn_deg,
        )
        return
    if declared:
        raise InputError(
            "--accel-units, --gyro-units, --time-units, --rate and --known-turn-deg describe "
            "a raw stream: use them with --stream"
        )
    from station.domain.calibration import (
        CalibrationError,
        Uncertainty,
        accelerometer_budget,
        solve,
    )
    from station.domain.limits import load_profile
    from station.domain.posefile import read_pose_file

    max_residual = load_profile(limits, profile).max_residual_counts
    pose_file = read_pose_file(file)
    try:
        solution = solve(pose_file.poses, model.value, max_residual_counts=max_residual)
    except CalibrationError as exc:
        raise InputError(f"{pose_file.where(exc.pose)}: {exc}") from None
    budget = accelerometer_budget(solution, pose_file.poses, pose_file.spread, pose_file.samples)
    uncertainty = Uncertainty.of_budget(budget)
    if as_json:
        print_json(solution.to_dict() | {"uncertainty": uncertainty.to_dict()})
    else:
        out.print(_table(solution, pose_file, uncertainty))


def _table(solution: Solution, pose_file: PoseFile, uncertainty: Uncertainty) -> Table:
    from station.domain.calibration import MIN_DOF_SHOWN, SENSITIVITY_CONVENTION

    cal, q = solution.calibration, solution.quality
    se = solution.standard_errors
    shown = se is not None and se.dof >= MIN_DOF_SHOWN
    table = Table(
        title=f"{pose_file.path}: {solution.poses} poses, {cal.model}-parameter model "
        f"({solution.method})"
    )
    table.add_column("axis")
    table.add_column("offset (counts)", justify="right")
    table.add_column("sensitivity (counts/g)", justify="right")
    table.add_column(f"U offset (k = {uncertainty.k:g})", justify="right")
    table.add_column(f"U sensitivity (k = {uncertainty.k:g})", justify="right")
    u_off, u_sens = uncertainty.offset, uncertainty.sensitivity
    for i, axis in enumerate(AXES):
        off = f"{cal.offset[i]:.4f}"
        sens = f"{cal.sensitivity[i]:.4f}"
        if shown and se is not None:
            off += f" ± {se.offset[i]:.4f}"
            sens += f" ± {se.sensitivity[i]:.4f}"
        table.add_row(
            axis,
            off,
            sens,
            "—" if u_off is None else f"± {u_off[i]:.4f}",
            "—" if u_sens is None else f"± {u_sens[i]:.4f}",
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
        lines.append(
            f"studentised residual max {q.studentised_max_counts:.3g} counts "
            f"(limit {solution.residual_limit_counts:g}, {solution.checked_with}-parameter check)"
        )
    if solution.k is not None:
        lines.insert(0, f"k1 = {solution.k[0]:.6f}, k2 = {solution.k[1]:.6f}")
    if cal.model == "nine":
        lines.append(f"sensitivity = {SENSITIVITY_CONVENTION['nine']}")
        lines.append(
            "matrix (counts → g): "
            + "; ".join(" ".join(f"{v:+.6e}" for v in row) for row in cal.matrix)
        )
    if q.near_duplicates:
        lines.insert(
            0,
            f"NOTE near-duplicates: {q.near_duplicates} poses lie within 10° of another "
            "(they add little; least squares needs no rule against them)",
        )
    for pose in solution.excluded:
        lines.insert(
            0,
            f"EXCLUDED pose {pose + 1} ({pose_file.where(pose)}): inconsistent with the others, "
            f"{(q.pose_g[pose] - 1) * 819.2:+.1f} counts off; fit redone without it",
        )
    table.caption = "\n".join(lines)
    return table
