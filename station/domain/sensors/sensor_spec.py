"""A product's accelerometer and gyros as the station reads them: the one description
every count-valued judgement of a run follows.

The station judges a unit in its sensor's counts: the stillness limits
(:mod:`station.domain.signals.stillness`), the ADC rails, the pose it lies in
(:mod:`station.domain.signals.orientation`), the screening of its poses
(:mod:`station.domain.calibration.geometry`) and the limits profile. Where a bound is
physical (a tremor, a tilt, a datasheet spread) it is held in g here and turned into
counts with the sensor's ``counts_per_g``; where it is about noise it follows
``noise_g``; the rails are ``0 … adc_max``. :data:`PUTTER_SENSOR` is the putter's
(DIXX-A12: the KXM52 behind the 12-bit ADC, [Song2006]_ Table 1,
:mod:`station.domain.sensors.sensor`), the default of everything that takes a sensor.
"""

from typing import Annotated, Final, Self

from pydantic import BaseModel, ConfigDict, Field, model_validator

from station.domain.constants import MAX_RATE_HZ
from station.domain.sensors.record_bounds import WIRE_COUNTS_MAX
from station.domain.sensors.sensor import (
    ADC_BITS,
    CROSS_AXIS_TYPICAL,
    GYRO_DPS_PER_LSB,
    NOMINAL_OFFSET_COUNTS,
    NOMINAL_SENSITIVITY_COUNTS_PER_G,
    OFFSET_SPREAD_COUNTS,
    OFFSET_TEMPCO_COUNTS_PER_C,
    SENSITIVITY_TEMPCO_PER_C,
    SENSITIVITY_TOLERANCE,
)


class SensorSpec(BaseModel):
    """A product's accelerometer and gyros, as the station sees them on the wire.

    ``adc_bits``: the accelerometer's counts are ``0 … 2**adc_bits − 1`` (a signed
    digital sensor is sent offset binary); ``zero_g_counts`` and ``counts_per_g``: its
    nominal zero-g output and sensitivity; ``range_g``: its full scale, ± g;
    ``gyro_dps_per_lsb``: one count of the gyro rate field; ``sample_rate_hz``: the rate
    the unit streams at.
    """

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    adc_bits: Annotated[int, Field(ge=8, le=WIRE_COUNTS_MAX.bit_length())]
    zero_g_counts: Annotated[float, Field(ge=0)]
    counts_per_g: Annotated[float, Field(gt=0)]
    range_g: Annotated[float, Field(gt=0, le=200)]
    gyro_dps_per_lsb: Annotated[float, Field(gt=0, le=1)]
    sample_rate_hz: Annotated[int, Field(ge=1, le=MAX_RATE_HZ)]
    #: Datasheet spreads a unit's zero g (± g) and sensitivity (± fraction) lie within.
    zero_g_spread_g: Annotated[float, Field(ge=0, le=1)] = 0.25
    sensitivity_tolerance: Annotated[float, Field(ge=0, lt=1)] = 0.05
    #: White noise of a reading, g rms.
    noise_g: Annotated[float, Field(ge=0, le=1)] = 0.0012
    #: The datasheet's largest temperature coefficients of the zero g (± g/°C) and of the
    #: sensitivity (± fraction/°C): the uncertainty budget's temperature term
    #: (:mod:`station.domain.calibration.uncertainty`).
    offset_tempco_g_per_c: Annotated[float, Field(ge=0, le=0.1)] = (
        OFFSET_TEMPCO_COUNTS_PER_C / NOMINAL_SENSITIVITY_COUNTS_PER_G
    )
    sensitivity_tempco_per_c: Annotated[float, Field(ge=0, le=0.01)] = SENSITIVITY_TEMPCO_PER_C
    #: The datasheet's cross-axis sensitivity (± fraction): the six-parameter model's
    #: unmodelled coupling in the uncertainty budget's ``model`` term.
    cross_axis: Annotated[float, Field(ge=0, le=0.2)] = CROSS_AXIS_TYPICAL
    #: The datasheet's (or a measured) turn-on to turn-on repeatability of the gyro bias,
    #: deg/s, a standard deviation; None: not declared (named as left out of U).
    gyro_bias_repeatability_dps: Annotated[float, Field(ge=0, le=100)] | None = None

    @property
    def adc_max(self) -> int:
        """The largest count the accelerometer sends."""
        return (1 << self.adc_bits) - 1

    @model_validator(mode="after")
    def _range_fits_the_adc(self) -> Self:
        if self.zero_g_counts > self.adc_max:
            raise ValueError(
                f"zero_g_counts {self.zero_g_counts:g} beyond the ADC's {self.adc_max}"
            )
        reach = self.range_g * self.counts_per_g
        low, high = self.zero_g_counts - reach, self.zero_g_counts + reach
        if low < 0 or high > self.adc_max + 1:
            raise ValueError(
                f"±{self.range_g:g} g at {self.counts_per_g:g} counts/g around "
                f"{self.zero_g_counts:g} spans {low:g}…{high:g}, beyond the "
                f"{self.adc_bits}-bit ADC's 0…{self.adc_max}"
            )
        return self

    def counts(self, g: float) -> float:
        """``g`` (an acceleration, or a bound in g) in this sensor's counts."""
        return g * self.counts_per_g

    @property
    def zero_g_spread_counts(self) -> float:
        """The datasheet's spread of a unit's zero g, ± counts."""
        return self.counts(self.zero_g_spread_g)

    @property
    def offset_tempco_counts_per_c(self) -> float:
        """The datasheet's largest temperature coefficient of the zero g, ± counts/°C."""
        return self.counts(self.offset_tempco_g_per_c)


#: The putter's sensor (DIXX-A12): the KXM52-1050 behind the 12-bit ADS7829, ±2 g,
#: ratiometric at 3.3 V, its spreads and its ~1 count rms of noise ([Song2006]_ Table 1).
PUTTER_SENSOR: Final = SensorSpec(
    adc_bits=ADC_BITS,
    zero_g_counts=NOMINAL_OFFSET_COUNTS,
    counts_per_g=NOMINAL_SENSITIVITY_COUNTS_PER_G,
    range_g=2.0,
    gyro_dps_per_lsb=GYRO_DPS_PER_LSB,
    sample_rate_hz=500,
    zero_g_spread_g=OFFSET_SPREAD_COUNTS / NOMINAL_SENSITIVITY_COUNTS_PER_G,
    sensitivity_tolerance=SENSITIVITY_TOLERANCE,
    noise_g=1.0 / NOMINAL_SENSITIVITY_COUNTS_PER_G,
)
