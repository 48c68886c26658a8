"""``calstation solve LOG.csv --stream``: the whole unit from a recorded raw stream.

Still poses, accelerometer, gyro bias and gyro matrix K ([Tedaldi2014]_) by
:func:`station.domain.gyro.motion.calibrate_stream`; the file format is in
:mod:`station.domain.gyro.motion.stream_file`.
"""

# Light to import, as the command modules are: its work is imported when it runs.

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from rich.table import Table

from station.cli.output import out, print_json
from station.domain.errors import InputError
from station.domain.sensor import AXES

if TYPE_CHECKING:
    from station.domain.calibration import Model
    from station.domain.gyro.motion import StreamCalibration
    from station.domain.gyro.motion.stream_units import StreamUnits


def solve_stream(
    file: Path,
    model: Model,
    *,
    as_json: bool,
    still_window_s: float,
    units: StreamUnits | None = None,
    known_turn_deg: float | None = None,
) -> None:
    """Calibrate the unit recorded in ``file`` (its columns in ``units``: the station's
    own by default; its whole turns of ``known_turn_deg``, if it declares them) and print
    the result."""
    from station.domain.calibration import CalibrationError
    from station.domain.gyro.motion import (
        GyroMatrixError,
        StreamError,
        calibrate_stream,
        stream_thresholds,
    )
    from station.domain.gyro.motion.stream_file import read_stream_file
    from station.domain.gyro.motion.stream_units import StreamUnits, check_units, convert

    declared = units or StreamUnits()
    try:
        stream = convert(read_stream_file(file), declared)
        check_units(stream, declared)
        result = calibrate_stream(
            stream,
            model,
            thresholds=stream_thresholds(stream.rate_hz, still_window_s),
            known_turn_deg=known_turn_deg,
        )
    except CalibrationError as exc:
        where = "" if exc.pose is None else f" (still pose {exc.pose} from 0)"
        raise InputError(f"{file}: accelerometer{where}: {exc}") from None
    except (StreamError, GyroMatrixError) as exc:
        raise InputError(f"{file}: {exc}") from None
    if as_json:
        print_json(result.to_dict())
    else:
        out.print(_table(result, file, stream.rate_hz))


def _table(result: StreamCalibration, file: Path, rate_hz: float) -> Table:
    import numpy as np

    cal, gyro = result.accel.calibration, result.gyro
    se = gyro.standard_errors
    table = Table(
        title=f"{file}: {len(result.stills)} still poses at {rate_hz:.4g} samples/s, "
        f"{cal.model}-parameter accelerometer, {len(gyro.used)} moves"
    )
    table.add_column("axis")
    table.add_column("offset (counts)", justify="right")
    table.add_column("sensitivity (counts/g)", justify="right")
    table.add_column("gyro bias (deg/s)", justify="right")
    u = result.uncertainty
    for i, axis in enumerate(AXES):
        table.add_row(
            axis,
            _with_u(cal.offset[i], u.offset, i, 3),
            _with_u(cal.sensitivity[i], u.sensitivity, i, 3),
            _with_u(result.bias_dps[i], u.gyro_bias_dps, i, 4, sign=True),
        )
    lines = [
        f"gyro K {axis}: "
        + "  ".join(f"{v:+.5f} ±{se[i, j]:.5f}" for j, v in enumerate(gyro.scale_matrix[i]))
        for i, axis in enumerate(AXES)
    ]
    lines.append(
        f"± in the table: expanded uncertainty U, k = {u.k:g} (docs/calibration.md); "
        f"± of K: 1-σ standard errors (U = {u.k:g}σ)"
    )
    lines += [
        f"accelerometer residual |g|−1: rms {result.accel.quality.residual_rms_mg:.3f} mg",
        f"moves: residual rms {gyro.residual_rms_deg:.3f}° with K, "
        f"median {float(np.median(gyro.residual_identity_deg)):.3f}° without (K = I)",
    ]
    lines += [f"move {u.index} unusable: {u.reason}" for u in gyro.unusable]
    table.caption = "\n".join(lines)
    return table


def _with_u(value: float, u: object, i: int, digits: int, *, sign: bool = False) -> str:
    """``value ± U`` with ``digits`` decimals (no ± when there is no U)."""
    import numpy as np

    shown = f"{value:+.{digits}f}" if sign else f"{value:.{digits}f}"
    if not isinstance(u, np.ndarray):
        return shown
    return f"{shown} ± {float(u[i]):.{digits}f}"
