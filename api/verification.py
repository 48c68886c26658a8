"""The server's own check of a submitted calibration: solve the poses again, compare.

A station sends the mean counts of every pose and the coefficients it wrote into the
unit; the server recomputes them with :func:`station.domain.calibration.solve` from the ``fit``
poses (with the residual limit of the run's own limits profile, so a pose the station
left out as inconsistent is left out again) and refuses the run when they disagree beyond
the tolerances below, or when the poses left out differ.

The poses are screened as the station screened them: in the counts of the run's own
product's sensor (its rails, its counts per g; a DIXX-D16 run in 16-bit counts, never the
12-bit putter's). A product this server does not ship (a station's own products file) has
no sensor here: its run is re-solved over the wire's whole range, with the sensitivity the
station submitted as counts per g; the arithmetic is checked, its rails were the
station's to check.
"""

import numpy as np

from station.domain.calibration import CalibrationError, GeometryLimits, solve
from station.domain.errors import CalstationError
from station.domain.product.limits import profile_of
from station.domain.record.records import Coefficients, RunRecord
from station.domain.sensors.record_bounds import WIRE_COUNTS_MAX
from station.domain.sensors.sensor_spec import PUTTER_SENSOR, SensorSpec

#: Offsets may differ by this much, counts (floating-point noise is ~1e-9).
OFFSET_TOLERANCE_COUNTS = 1e-3
#: Sensitivities and matrix entries may differ by this fraction.
RELATIVE_TOLERANCE = 1e-6


class CalibrationMismatchError(CalstationError):
    """The submitted coefficients are not what the submitted poses give."""


def _shipped_sensor(part_number: str) -> SensorSpec | None:
    """The sensor of the shipped product ``part_number`` (None: not one this server ships)."""
    # Imported here: the products read their run plans, whose poses import scipy, which
    # the server's start does without (tests/api/test_start.py).
    from station.domain.product.products import shipped_sensor

    return shipped_sensor(part_number)


def counts_beyond_sensor(record: RunRecord) -> str | None:
    """The first pose mean of ``record`` beyond the ADC range of its shipped product's
    sensor, named (a product this server does not ship: none, the record itself holds
    the wire's range)."""
    sensor = _shipped_sensor(record.part_number)
    return None if sensor is None else record.counts_beyond(sensor.adc_max)


def sensor_of(record: RunRecord, submitted: Coefficients) -> SensorSpec:
    """The sensor whose counts ``record``'s poses are: its shipped product's, or for a
    product this server does not know, the wire's range at the submitted sensitivity."""
    shipped = _shipped_sensor(record.part_number)
    if shipped is not None:
        return shipped
    counts_per_g = max(float(np.mean(np.abs(submitted.sensitivity.as_tuple()))), 1.0)
    middle = WIRE_COUNTS_MAX / 2
    return PUTTER_SENSOR.model_copy(
        update={
            "adc_bits": WIRE_COUNTS_MAX.bit_length(),
            "zero_g_counts": middle,
            "counts_per_g": counts_per_g,
            "range_g": min(200.0, middle / counts_per_g),
        }
    )


def check_coefficients(record: RunRecord) -> None:
    """Raise :class:`CalibrationMismatchError` unless the poses give the submitted coefficients.

    A failing run without coefficients (the station could not calibrate) has nothing to
    check.
    """
    submitted = record.coefficients
    if submitted is None:
        return
    poses = np.array([pose.mean.as_tuple() for pose in record.fit_poses()])
    profile = profile_of(record.limits)
    limit = None if profile is None else profile.max_residual_counts
    try:
        solution = solve(
            poses,
            model=record.model,
            limits=GeometryLimits(sensor=sensor_of(record, submitted)),
            max_residual_counts=limit,
        )
    except (CalibrationError, np.linalg.LinAlgError, FloatingPointError) as exc:
        # Numerical failures on absurd poses are the poses' fault too, not the server's.
        raise CalibrationMismatchError(
            f"coefficients submitted but the fit poses give no calibration: {exc}"
        ) from None
    recomputed = solution.calibration
    excluded = record.quality.excluded_poses if record.quality is not None else None
    if solution.excluded != (excluded or ()):
        shown = ", ".join(str(p) for p in solution.excluded) or "none"
        raise CalibrationMismatchError(
            f"quality.excluded_poses: submitted {list(excluded or ())}, the poses give [{shown}]"
        )
    offset = np.array(submitted.offset.as_tuple())
    sensitivity = np.array(submitted.sensitivity.as_tuple())
    matrix = np.array(submitted.matrix)
    checks = (
        ("offset", offset, recomputed.offset, OFFSET_TOLERANCE_COUNTS, 0.0),
        ("sensitivity", sensitivity, recomputed.sensitivity, 0.0, RELATIVE_TOLERANCE),
        ("matrix", matrix, recomputed.matrix, 1e-12, RELATIVE_TOLERANCE),
    )
    for name, given, expected, atol, rtol in checks:
        if not np.allclose(given, expected, atol=atol, rtol=rtol):
            worst = np.unravel_index(np.argmax(np.abs(given - expected)), given.shape)
            where = "".join(f"[{i}]" for i in worst)
            raise CalibrationMismatchError(
                f"{name}{where}: submitted {given[worst]:.6g}, the poses give "
                f"{expected[worst]:.6g} ({record.model} model, {len(poses)} fit poses)"
            )
