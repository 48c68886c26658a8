"""``calstation solve FILE``: calibrate from a file of still-pose means."""

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from station.calibration import CalibrationError, Solution, solve
from station.cli.output import out, print_json
from station.cli.solve_stream import solve_stream
from station.errors import InputError
from station.gyro.motion.stream import STILL_WINDOW_S
from station.posefile import read_pose_file
from station.sensor import AXES


class ModelChoice(StrEnum):
    """The calibration models offered on the command line."""

    six = "six"
    nine = "nine"


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
) -> None:
    """Compute offsets and sensitivities from still-pose means (ADC counts)."""
    if stream:
        solve_stream(file, model.value, as_json=as_json, still_window_s=still_window)
        return
    pose_file = read_pose_file(file)
    try:
        solution = solve(pose_file.poses, model.value)
    except CalibrationError as exc:
        raise InputError(f"{pose_file.where(exc.pose)}: {exc}") from None
    if as_json:
        print_json(solution.to_dict())
    else:
        out.print(_table(solution, file))


def _table(solution: Solution, file: Path) -> Table:
    cal, q = solution.calibration, solution.quality
    se = solution.standard_errors
    table = Table(
        title=f"{file}: {solution.poses} poses, {cal.model}-parameter model ({solution.method})"
    )
    table.add_column("axis")
    table.add_column("offset (counts)", justify="right")
    table.add_column("sensitivity (counts/g)", justify="right")
    for i, axis in enumerate(AXES):
        off = f"{cal.offset[i]:.4f}"
        sens = f"{cal.sensitivity[i]:.4f}"
        if se is not None:
            off += f" ± {se.offset[i]:.4f}"
            sens += f" ± {se.sensitivity[i]:.4f}"
        table.add_row(axis, off, sens)
    lines = [
        f"residual |g|−1: rms {q.residual_rms_mg:.3f} mg, max {q.residual_max_mg:.3f} mg",
        f"condition number {q.condition_number:.3g}, coverage {q.coverage:.3f}, "
        f"closest poses {q.min_angle_deg:.1f}°",
    ]
    if solution.k is not None:
        lines.insert(0, f"k1 = {solution.k[0]:.6f}, k2 = {solution.k[1]:.6f}")
    if cal.model == "nine":
        lines.append(
            "matrix (counts → g): "
            + "; ".join(" ".join(f"{v:+.6e}" for v in row) for row in cal.matrix)
        )
    table.caption = "\n".join(lines)
    return table
