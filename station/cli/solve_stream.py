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
    still_window_s: float | None,
    units: StreamUnits | None = None,
    known_turn_deg: float | None = None,
    tempco: tuple[float, float] | None = None,
    cross_axis_bound: float | None = None,
    gyro_bias_repeatability_dps: float | None = None,
) -> None:
    """Calibrate the unit recorded in ``file`` (its columns in ``units``: the station's
    own by default; its whole turns of ``known_turn_deg``, if it declares them; its
    sensor's temperature coefficients ``tempco``, counts/°C and /°C, and cross-axis
    sensitivity ``cross_axis_bound``, the putter's by default; its gyros' declared bias
    repeatability, if any) and print the result."""
    from station.cli.solve import excluded, influence_lines, temperature_summary
    from station.domain.calibration import CalibrationError
    from station.domain.calibration.uncertainty import (
        CROSS_AXIS_BOUND,
        OFFSET_TEMPCO_BOUND,
        SENSITIVITY_TEMPCO_BOUND,
    )
    from station.domain.gyro.motion import (
        GyroMatrixError,
        StreamError,
        calibrate_stream,
        stream_thresholds,
    )
    from station.domain.gyro.motion.stream_file import read_stream_file
    from station.domain.gyro.motion.stream_units import (
        StreamUnits,
        check_declared,
        check_turns,
        check_units,
        convert,
    )

    declared = units or StreamUnits()
    try:
        raw = read_stream_file(file)
        check_declared(raw, declared)
        stream = convert(raw, declared)
        check_units(stream, declared)
        result = calibrate_stream(
            stream,
            model,
            thresholds=None
            if still_window_s is None
            else stream_thresholds(stream.rate_hz, still_window_s),
            known_turn_deg=known_turn_deg,
            check_moves=lambda moves, bias: check_turns(moves, bias, declared),
            tempco=tempco or (OFFSET_TEMPCO_BOUND, SENSITIVITY_TEMPCO_BOUND),
            cross_axis_bound=CROSS_AXIS_BOUND if cross_axis_bound is None else cross_axis_bound,
            gyro_bias_repeatability_dps=gyro_bias_repeatability_dps,
        )
    except CalibrationError as exc:
        where = "" if exc.pose is None else f" (still pose {exc.pose} from 0)"
        raise InputError(f"{file}: accelerometer{where}: {exc}") from None
    except (StreamError, GyroMatrixError) as exc:
        raise InputError(f"{file}: {exc}") from None
    accel = declared.accelerometer
    temperature = temperature_summary(result.temperatures)
    if as_json:
        print_json(
            declared.restate_gyro(accel.restate(result.to_dict()))
            | {
                "units": _units(declared),
                "temperature_c": temperature,
                "excluded_influences": excluded(result.excluded_influences),
            }
        )
    else:
        table = _table(result, file, stream.rate_hz, declared)
        notes = [
            f"DISTURBED still pose {pose + 1}: its spread is {ratio:.3g}× the stills' noise: "
            "its excess counted in U undivided by its sample count"
            for pose, ratio in result.disturbed.items()
        ]
        table.caption = "\n".join(
            [*notes, str(table.caption), *influence_lines(temperature, result.excluded_influences)]
        )
        out.print(table)


def _units(declared: StreamUnits) -> dict[str, str]:
    """The JSON's ``units``: the accelerometer's and the gyro bias' as declared."""
    return declared.accelerometer.names() | {"gyro_bias": declared.gyro_name, "gyro_matrix": "1"}


def _table(result: StreamCalibration, file: Path, rate_hz: float, declared: StreamUnits) -> Table:
    import numpy as np

    from station.cli.solve import unit_decimals, unit_headers

    units = declared.accelerometer
    cal, gyro = result.accel.calibration, result.gyro
    fitted = f"{len(result.moves)} moves" if gyro is None else f"{len(gyro.used)} moves fitted"
    table = Table(
        title=f"{file}: {len(result.stills)} still poses (still window "
        f"{result.still_window_s:.3g} s) at {rate_hz:.4g} samples/s, "
        f"{cal.model}-parameter accelerometer, {fitted}"
    )
    offset_header, sensitivity_header = unit_headers(units)
    table.add_column("axis")
    table.add_column(offset_header, justify="right")
    table.add_column(sensitivity_header, justify="right")
    table.add_column(f"gyro bias ({declared.gyro_name})", justify="right")
    u = result.uncertainty
    do, ds = unit_decimals(units, 3)
    offset, sensitivity = units.offset(cal.offset), units.sensitivity(cal.sensitivity)
    u_off = None if u.offset is None else units.spread(u.offset)
    u_sens = None if u.sensitivity is None else units.sensitivity(u.sensitivity)
    bias = declared.gyro_rate(result.bias_dps)
    u_bias = None if u.gyro_bias_dps is None else declared.gyro_rate(u.gyro_bias_dps)
    # 4 decimals of deg/s; rad/s is 57 times smaller: two more.
    db = 4 if declared.gyro == "dps" else 6
    for i, axis in enumerate(AXES):
        table.add_row(
            axis,
            _with_u(offset[i], u_off, i, do),
            _with_u(sensitivity[i], u_sens, i, ds),
            _with_u(bias[i], u_bias, i, db, sign=True),
        )
    accel_line = f"accelerometer residual |g|−1: rms {result.accel.quality.residual_rms_mg:.3f} mg"
    if gyro is None:
        table.caption = "\n".join(
            [
                f"gyro K not determined: {result.gyro_not_determined}",
                f"± in the table: U (k={u.k:g}), expanded uncertainty (docs/calibration.md)",
                accel_line,
            ]
        )
        return table
    # The JSON's U of K (the fit, the moves' geometry and the model's coupling), not
    # the fit's standard errors: one U on every screen. A fitted K always has one.
    u_k = u.gyro_matrix
    assert u_k is not None
    lines = [
        f"gyro K {axis}: "
        + "  ".join(f"{v:+.5f} ±{u_k[i, j]:.5f}" for j, v in enumerate(gyro.scale_matrix[i]))
        for i, axis in enumerate(AXES)
    ]
    lines.append(
        f"± in the table and of K: U (k={u.k:g}), expanded uncertainty (docs/calibration.md)"
    )
    lines += [
        accel_line,
        f"moves: residual rms {gyro.residual_rms_deg:.3f}° with K, "
        f"median {float(np.median(gyro.residual_identity_deg)):.3f}° without (K = I)",
    ]
    lines += [f"move {m.index} unusable: {m.reason}" for m in gyro.unusable]
    table.caption = "\n".join(lines)
    return table


def _with_u(value: float, u: object, i: int, digits: int, *, sign: bool = False) -> str:
    """``value ± U`` with ``digits`` decimals (no ± when there is no U)."""
    import numpy as np

    shown = f"{value:+.{digits}f}" if sign else f"{value:.{digits}f}"
    if not isinstance(u, np.ndarray):
        return shown
    return f"{shown} ± {float(u[i]):.{digits}f}"
