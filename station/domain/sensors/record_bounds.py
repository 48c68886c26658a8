"""The physical bounds of every number a run record holds: one place, used by the model.

A record that validates holds only values the putter and the station can produce, so
nothing downstream (the database's roll-ups, sums of squares, the JSON report) meets a
number it cannot handle. Each bound follows from the hardware ([Song2006]_ Table 1 and
the serial protocol), never from a limits profile: a failing unit's record must still be
storable, however bad the unit. A value outside them is a corrupted or forged record,
and the results server answers 422 naming the field.

Where a bound is derived from others (the largest error in mg), the derivation is in the
comment beside it, so that every record the station computes from in-range counts is
inside by construction (tests/station/test_record_bounds.py checks it).
"""

import re
from datetime import UTC, datetime
from typing import Annotated, Final, TypeVar

from pydantic import AfterValidator, BaseModel, Field, StringConstraints

from station.domain.sensors.sensor import ADC_MIN, GYRO_DPS_PER_LSB, TEMP_C_PER_LSB

#: The widest accelerometer reading any product's sensor sends, counts: the protocol's
#: u16 field (docs/protocol.md), which a 16-bit sensor fills (``station.domain.product.products``).
WIRE_COUNTS_MAX: Final = 65535

#: The widest ADC span of the products' sensors, counts: no spread of readings within
#: 0…65535 exceeds it (the pose means are bounded by the same 0…65535, any product's).
ADC_SPAN: Final = float(WIRE_COUNTS_MAX)

#: Largest gyro rate the putter can report, deg/s: the protocol's int16 rate field at
#: 0.02 deg/s per LSB (docs/protocol.md), 32768 × 0.02 = 655.36 deg/s. A mean of
#: readings, hence a bias, lies within ±this; a spread within twice it (the span).
GYRO_RANGE_DPS: Final = 32768 * GYRO_DPS_PER_LSB
GYRO_SPAN_DPS: Final = 2 * GYRO_RANGE_DPS

#: Temperatures the protocol's int16 field at 0.01 °C per LSB can carry: ±327.68 °C.
TEMPERATURE_RANGE_C: Final = 32768 * TEMP_C_PER_LSB

#: A zero-g output (offset) lies within one ADC span beyond either rail: the centre of
#: the ellipsoid through poses that are all inside 0…65535 and cover both sides of each
#: axis cannot lie further out.
OFFSET_MIN_COUNTS: Final = ADC_MIN - ADC_SPAN
OFFSET_MAX_COUNTS: Final = WIRE_COUNTS_MAX + ADC_SPAN

#: Sensitivity, counts/g: positive, and at most the whole ADC span per g (a sensor reading
#: more could not show +1 g and −1 g inside the converter's range; nominal 819.2 for the
#: 12-bit KXM52, 8192 for the 16-bit digital sensor).
SENSITIVITY_MAX_COUNTS_PER_G: Final = ADC_SPAN

#: A counts-to-g matrix entry, g/count: at most 1 (a sensor whose ±2 g range spanned four
#: counts; nominal 1/819.2 ≈ 0.0012).
MATRIX_MAX_G_PER_COUNT: Final = 1.0

#: An error or residual, mg. A record's pose means lie within the wire's 0…65535
#: (``station.domain.record.records.Counts3``), so an offset computed from them lies within
#: −65535…131070 and a calibrated reading is at most 3 × 1 g/count × (|offset − raw| ≤
#: 131,070 counts) ≈ 393,210 g per axis, √3 × that ≈ 681,060 g in magnitude: 6.8e8 mg.
#: 1e9 mg keeps every record computed from in-range counts valid.
ERROR_MAX_MG: Final = 1e9

#: The solve's condition number of a fit the station accepts is at most
#: :data:`station.domain.calibration.residual.MAX_CONDITION` (1e3); a record may say up to 1e6.
CONDITION_MAX: Final = 1e6

#: A check's measured value or bound (failure reasons): any unit, so only a magnitude
#: whose square is still a finite double.
MEASURE_MAX: Final = 1e150

#: A run's duration: a unit's poses are taken within a shift; one resumed from its
#: journal after a long stop may span days; a run of more than 31 days is not a run.
RUN_MAX_DAYS: Final = 31

#: The years (UTC) a run the results server stores may start and end in. A station
#: stamps its runs with its own clock; one that lost its time or was set by hand (the
#: year 1, the year 9999) stamps a moment no report asks about, so the server refuses
#: it (422 naming the field) rather than file it there. Stored runs are not checked
#: again, and a station's own database stores any time of the years 1…9999: the
#: roll-ups hold either (:mod:`db.rollups`).
RUN_YEARS: Final = (2000, 2199)


def implausible_run_time(moment: datetime) -> str | None:
    """Why ``moment`` cannot be a run's start or end (outside :data:`RUN_YEARS` in UTC),
    or None when it can."""
    first, last = RUN_YEARS
    if first <= moment.astimezone(UTC).year <= last:
        return None
    shown = moment.astimezone(UTC).isoformat().replace("+00:00", "Z")
    return f"{shown} is outside the years {first}…{last} (UTC): the station's clock is wrong"


GyroRate = Annotated[float, Field(ge=-GYRO_RANGE_DPS, le=GYRO_RANGE_DPS)]
"""A gyro reading or a mean of readings (bias), deg/s."""

GyroSpread = Annotated[float, Field(ge=0, le=GYRO_SPAN_DPS)]
"""A spread (standard deviation, RMS noise) of gyro readings, deg/s."""

Temperature = Annotated[float, Field(ge=-TEMPERATURE_RANGE_C, le=TEMPERATURE_RANGE_C)]
"""A temperature the unit reports, °C."""

ErrorMg = Annotated[float, Field(ge=0, le=ERROR_MAX_MG)]
"""A residual or verification error, mg."""

ConditionNumber = Annotated[float, Field(ge=1, le=CONDITION_MAX)]
"""The calibration solve's condition number."""

Measure = Annotated[float, Field(ge=-MEASURE_MAX, le=MEASURE_MAX)]
"""A check's measured value or bound, or a fitted slope, in its own unit."""

Probability = Annotated[float, Field(ge=0, le=1)]
"""A p-value or significance level."""

#: A control character: Unicode category Cc (C0 controls, NUL and line breaks among them,
#: DEL, C1 controls). Searched for anywhere in a text: a ``^[^…]*$`` matched with
#: ``re.match`` let a trailing newline through, since ``$`` matches before one.
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f]")


def printable(text: str) -> str:
    """``text`` unchanged; ValueError if it holds a control character anywhere, a trailing
    newline included (NUL included: a PostgreSQL text or JSON value cannot hold one).

    The one check of every free text a record, a review or a limits profile holds.
    """
    if _CONTROL.search(text):
        raise ValueError("must not contain control characters")
    return text


Text = Annotated[str, StringConstraints(max_length=500), AfterValidator(printable)]
"""Free text for people (messages, reasons): one line, no control characters."""

M = TypeVar("M", bound=BaseModel)


def _plain(value: object, where: str) -> None:
    if isinstance(value, str) and _CONTROL.search(value):
        raise ValueError(f"{where or 'text'} must not contain control characters")
    if isinstance(value, float) and not -MEASURE_MAX <= value <= MEASURE_MAX:
        raise ValueError(f"{where or 'number'} {value:.6g} is not a number within ±{MEASURE_MAX:g}")
    if isinstance(value, dict | list | tuple):
        items = value.items() if isinstance(value, dict) else enumerate(value)
        for key, item in items:
            _plain(item, f"{where}.{key}" if where else str(key))


def plain_document(document: M) -> M:
    """``document`` unchanged; ValueError naming the first text holding a control
    character or number outside ±:data:`MEASURE_MAX` (NaN included) anywhere in it.

    For the models stored whole as one JSON document (a gyro fit and its dwells), whose
    many fields are free-form lists: PostgreSQL's JSON refuses NUL and NaN.
    """
    _plain(document.model_dump(), "")
    return document
