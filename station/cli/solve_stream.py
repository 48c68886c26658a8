"""``calstation solve LOG.csv --stream``: the whole unit from a recorded raw stream.

Still poses, accelerometer, gyro bias and gyro matrix K ([Tedaldi2014]_) by
:func:`station.domain.gyro.motion.calibrate_stream`; the file format is in
:mod:`station.domain.gyro.motion.stream_file`.
"""

# Light to import, as the command modules are: its work is imported when it runs.

from __future__ import annotations

from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

from rich.table import Table

from station.cli.output import out, print_json
from station.domain.errors import InputError
from station.domain.sensors.sensor import AXES

if TYPE_CHECKING:
    from station.domain.arrays import FloatArray
    from station.domain.calibration import Model
    from station.domain.gyro.motion import StreamCalibration
    from station.domain.gyro.motion.stream_units import StreamUnits


def solve_stream(
    files: list[Path],
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
    """Calibrate the unit recorded in ``files`` (its columns in ``units``: the station's
    own by default; its whole turns of ``known_turn_deg``, if it declares them; its
    sensor's temperature coefficients ``tempco``, counts/°C and /°C, and cross-axis
    sensitivity ``cross_axis_bound``, the putter's by default; its gyros' declared bias
    repeatability, if any) and print the result.

    Several files are power-on sessions of one unit: each is calibrated, the sessions'
    gyro biases give the bias' turn-on to turn-on repeatability
    (:func:`~station.domain.calibration.uncertainty.gyro_bias_repeatability`), and each
    session's gyro-bias U holds that measured figure in place of a declared one."""
    import numpy as np

    from station.domain.calibration.uncertainty import gyro_bias_repeatability
    from station.domain.gyro.motion.stream_units import StreamUnits

    declared = units or StreamUnits()
    session = partial(
        _calibrated,
        model=model,
        still_window_s=still_window_s,
        declared=declared,
        known_turn_deg=known_turn_deg,
        tempco=tempco,
        cross_axis_bound=cross_axis_bound,
    )
    if len(files) == 1:
        result, rate_hz = session(files[0], repeatability_dps=gyro_bias_repeatability_dps)
        _print(result, files[0], rate_hz, declared, as_json=as_json)
        return
    if gyro_bias_repeatability_dps is not None:
        raise InputError(
            f"--gyro-bias-repeatability: declared, but {len(files)} sessions measure it: "
            "leave it out, or give one recording"
        )
    biases = np.array([session(f, repeatability_dps=None)[0].bias_dps for f in files])
    measured = gyro_bias_repeatability(biases)
    sessions = [(f, *session(f, repeatability_dps=measured)) for f in files]
    shown = declared.gyro_rate(measured)
    if as_json:
        payloads = [_payload(result, declared) | {"file": str(f)} for f, result, _ in sessions]
        print_json(
            {
                "sessions": payloads,
                "gyro_bias_repeatability": {
                    "sessions": len(files),
                    "degrees_of_freedom": len(files) - 1,
                    "value": [float(v) for v in shown],
                    "biases": [[float(v) for v in declared.gyro_rate(b)] for b in biases],
                    "unit": declared.gyro_name,
                },
            }
        )
        return
    for f, result, rate_hz in sessions:
        _print(result, f, rate_hz, declared, as_json=False)
    values = "  ".join(f"{axis} {v:.4g}" for axis, v in zip(AXES, shown, strict=True))
    out.print(
        f"gyro bias repeatability measured across {len(files)} sessions "
        f"({len(files) - 1} degrees of freedom): {values} {declared.gyro_name} (1 σ), "
        "in each session's U"
    )


def _calibrated(
    file: Path,
    *,
    model: Model,
    still_window_s: float | None,
    declared: StreamUnits,
    known_turn_deg: float | None,
    tempco: tuple[float, float] | None,
    cross_axis_bound: float | None,
    repeatability_dps: float | FloatArray | None,
) -> tuple[StreamCalibration, float]:
    """One recording calibrated (:func:`solve_stream`), and its sample rate."""
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
        check_declared,
        check_turns,
        check_units,
        convert,
    )

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
            gyro_bias_repeatability_dps=repeatability_dps,
        )
    except CalibrationError as exc:
        where = "" if exc.pose is None else f" (still pose {exc.pose} from 0)"
        raise InputError(f"{file}: accelerometer{where}: {exc}") from None
    except (StreamError, GyroMatrixError) as exc:
        raise InputError(f"{file}: {exc}") from None
    return result, stream.rate_hz


def _payload(result: StreamCalibration, declared: StreamUnits) -> dict[str, object]:
    """The JSON of one recording's calibration, in its declared units."""
    from station.cli.solve import excluded, temperature_summary

    return declared.restate_gyro(declared.accelerometer.restate(result.to_dict())) | {
        "units": _units(declared),
        "temperature_c": temperature_summary(result.temperatures),
        "excluded_influences": excluded(result.excluded_influences),
    }


def _print(
    result: StreamCalibration, file: Path, rate_hz: float, declared: StreamUnits, *, as_json: bool
) -> None:
    """One recording's calibration on the screen, or as JSON."""
    from station.cli.solve import influence_lines, temperature_summary

    if as_json:
        print_json(_payload(result, declared))
        return
    table = _table(result, file, rate_hz, declared)
    notes = [
        f"DISTURBED still pose {pose + 1}: its spread is {ratio:.3g}× the stills' noise: "
        "its excess counted in U undivided by its sample count"
        for pose, ratio in result.disturbed.items()
    ]
    temperature = temperature_summary(result.temperatures)
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
