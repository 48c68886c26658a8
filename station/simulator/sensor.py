"""Sensor model of the virtual putter: accelerometer behind the ADC, and the gyros.

Accelerometer ([Song2006]_ Table 1 and eq. 5, extended by cross-axis coupling and
temperature), per sample, in ADC counts::

    a = o(T) + diag(s(T)) · C · f + n,      then rounded and clipped to 0…4095
    o(T) = o₂₅ + k_o · (T − 25 °C)          s(T) = s₂₅ · (1 + k_s · (T − 25 °C))

``f`` is the specific force in body axes (g), ``C`` the cross-axis matrix (unit
diagonal, off-diagonal terms up to 2 %), ``n`` white noise. The unit's true
counts-to-g map is therefore ``M = (diag(s) · C)⁻¹``, ``g = M · (a − o)``.

Gyros ([Park2014]_ eq. 4), per axis i, in deg/s::

    ω̃_i = ω_i + β_i + Σ_{j≠i} β_ij ω_j + β_ii ω_i + G_ii · f_sense(i) · ω_i + n

with ``f_sense(i)`` the specific force along gyro i's sense (detection) axis,
:data:`GYRO_SENSE_AXIS`. Acceleration alone, or along another axis, gives no error,
as the paper found on the centrifuge.
"""

from dataclasses import dataclass, replace
from typing import Any, Final

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.sensors.sensor import (
    ADC_MAX,
    ADC_MIN,
    CROSS_AXIS_TYPICAL,
    NOMINAL_OFFSET_COUNTS,
    NOMINAL_SENSITIVITY_COUNTS_PER_G,
    OFFSET_SPREAD_COUNTS,
    SENSITIVITY_TOLERANCE,
)
from station.domain.sensors.sensor_spec import SensorSpec

#: Sense axis of each gyro (x, y, z): the tuning forks detect along y, z and x.
GYRO_SENSE_AXIS: Final = (1, 2, 0)
REFERENCE_TEMPERATURE_C: Final = 25.0
#: Accelerometer white noise, counts rms (KXM52 ~1 mg rms in the board's bandwidth).
ACCEL_NOISE_COUNTS: Final = 1.0
#: Gyro white noise, deg/s rms per sample.
GYRO_NOISE_DPS: Final = 0.08
#: Largest gyro bias drawn, deg/s (below the stillness detector's rate threshold).
GYRO_BIAS_MAX_DPS: Final = 0.3
#: Scale-factor g-sensitivity of [Park2014]_ (X 581, Y 612, Z −613 ppm/g), nominal magnitude.
GYRO_G_SENSITIVITY_PER_G: Final = 600e-6


@dataclass(frozen=True)
class SensorTruth:
    """The true parameters of one virtual unit (at 25 °C), for checking a calibration."""

    offset_counts: FloatArray
    sensitivity_counts_per_g: FloatArray
    cross_axis: FloatArray
    noise_counts: float
    offset_tempco_counts_per_c: FloatArray
    sensitivity_tempco_per_c: FloatArray
    gyro_bias_dps: FloatArray
    gyro_scale_error: FloatArray
    gyro_misalignment: FloatArray
    gyro_g_sensitivity_per_g: FloatArray
    gyro_noise_dps: float
    #: The largest count the unit's ADC gives (the putter's 12-bit one unless its
    #: product's sensor says otherwise, :meth:`draw`).
    adc_max: int = ADC_MAX

    @property
    def matrix(self) -> FloatArray:
        """The true counts-to-g matrix ``(diag(s) · C)⁻¹`` at 25 °C."""
        return np.asarray(
            np.linalg.inv(np.diag(self.sensitivity_counts_per_g) @ self.cross_axis),
            dtype=np.float64,
        )

    @property
    def gyro_matrix(self) -> FloatArray:
        """The true gyro matrix K in body axes, ``I + diag(scale error) + misalignment``
        (``measured = bias + K·ω`` apart from g-sensitivity and noise)."""
        return np.asarray(
            np.eye(3) + np.diag(self.gyro_scale_error) + self.gyro_misalignment, dtype=np.float64
        )

    @property
    def counts_per_g(self) -> FloatArray:
        """The accelerometer's counts-per-g matrix ``S = diag(s) · C`` at 25 °C (the inverse
        of :attr:`matrix`): a unit at rest reads ``o + S · f``."""
        return np.asarray(
            np.diag(self.sensitivity_counts_per_g) @ self.cross_axis, dtype=np.float64
        )

    def at(self, temperature_c: float) -> "SensorTruth":
        """The same unit with its offsets and sensitivities at ``temperature_c`` (module
        docstring: ``o(T)``, ``s(T)``), its temperature coefficients unchanged."""
        dt = temperature_c - REFERENCE_TEMPERATURE_C
        return replace(
            self,
            offset_counts=self.offset_counts + self.offset_tempco_counts_per_c * dt,
            sensitivity_counts_per_g=self.sensitivity_counts_per_g
            * (1 + self.sensitivity_tempco_per_c * dt),
        )

    def still_counts(self, force_g: FloatArray) -> FloatArray:
        """Noise-free accelerometer counts at 25 °C (N-by-3, not rounded, not clipped) for
        specific forces ``force_g`` (N-by-3, g): the mean of a long still window."""
        return np.asarray(self.offset_counts + force_g @ self.counts_per_g.T, dtype=np.float64)

    @classmethod
    def accelerometer(
        cls,
        offset_counts: FloatArray,
        counts_per_g: FloatArray,
        *,
        gyro_matrix: FloatArray | None = None,
        gyro_bias_dps: FloatArray | None = None,
    ) -> "SensorTruth":
        """A unit with this accelerometer (offsets, counts, and counts-per-g matrix
        ``S = diag(s) · C``) and these gyros (``K`` and bias, deg/s), perfect otherwise: no
        temperature drift, no g-sensitivity, no noise (noise is the recording's)."""
        sensitivity = np.diag(counts_per_g).astype(np.float64)
        k = np.eye(3) if gyro_matrix is None else np.asarray(gyro_matrix, dtype=np.float64)
        return cls(
            offset_counts=np.asarray(offset_counts, dtype=np.float64),
            sensitivity_counts_per_g=sensitivity,
            cross_axis=np.asarray(counts_per_g / sensitivity[:, None], dtype=np.float64),
            noise_counts=0.0,
            offset_tempco_counts_per_c=np.zeros(3),
            sensitivity_tempco_per_c=np.zeros(3),
            gyro_bias_dps=np.zeros(3) if gyro_bias_dps is None else gyro_bias_dps,
            gyro_scale_error=np.diag(k) - 1.0,
            gyro_misalignment=k - np.diag(np.diag(k)),
            gyro_g_sensitivity_per_g=np.zeros(3),
            gyro_noise_dps=0.0,
        )

    @classmethod
    def draw_accelerometer(
        cls,
        rng: np.random.Generator,
        cross_axis: float = 0.0,
        offset_spread: float = OFFSET_SPREAD_COUNTS,
        sensitivity_tolerance: float = SENSITIVITY_TOLERANCE,
    ) -> "SensorTruth":
        """An accelerometer drawn uniformly within the datasheet spreads ([Song2006]_
        Table 1), perfect gyros (:meth:`accelerometer`). ``cross_axis``: each off-diagonal
        coupling uniform in ±cross_axis (the KXM52's typical value is
        :data:`station.domain.sensors.sensor.CROSS_AXIS_TYPICAL`)."""
        offset = NOMINAL_OFFSET_COUNTS + rng.uniform(-offset_spread, offset_spread, 3)
        s = NOMINAL_SENSITIVITY_COUNTS_PER_G * (
            1 + rng.uniform(-sensitivity_tolerance, sensitivity_tolerance, 3)
        )
        coupling = rng.uniform(-cross_axis, cross_axis, (3, 3))
        np.fill_diagonal(coupling, 0.0)
        return cls.accelerometer(offset, np.diag(s) @ (np.eye(3) + coupling))

    @classmethod
    def draw(cls, rng: np.random.Generator, spec: SensorSpec | None = None) -> "SensorTruth":
        """A unit as the line meets them: every parameter within its datasheet spread;
        ``spec``: a product's sensor (:mod:`station.domain.product.products`; default the putter's
        KXM52 behind the 12-bit ADC), its accelerometer's nominal values, spreads, noise
        and ADC range."""
        cross = np.eye(3) + rng.uniform(-CROSS_AXIS_TYPICAL, CROSS_AXIS_TYPICAL, (3, 3)) * (
            1 - np.eye(3)
        )
        misalignment = rng.uniform(-0.005, 0.005, (3, 3)) * (1 - np.eye(3))
        if spec is None:
            zero_g, per_g, spread = NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G, None
            tolerance, noise, adc_max = SENSITIVITY_TOLERANCE, ACCEL_NOISE_COUNTS, ADC_MAX
        else:
            zero_g, per_g = spec.zero_g_counts, spec.counts_per_g
            spread = spec.zero_g_spread_g * per_g
            tolerance, noise, adc_max = (
                spec.sensitivity_tolerance,
                spec.noise_g * per_g,
                spec.adc_max,
            )
        spread = OFFSET_SPREAD_COUNTS if spread is None else spread
        return cls(
            offset_counts=zero_g + rng.uniform(-spread, spread, 3),
            sensitivity_counts_per_g=per_g * (1 + rng.uniform(-tolerance, tolerance, 3)),
            cross_axis=cross,
            noise_counts=noise,
            adc_max=adc_max,
            # ±100 mV over 60 °C is ±2 counts/°C at worst; typical units drift far less.
            offset_tempco_counts_per_c=rng.uniform(-0.5, 0.5, 3),
            # ±3 % over 60 °C at worst: ±0.05 %/°C; typical a fifth of it.
            sensitivity_tempco_per_c=rng.uniform(-1e-4, 1e-4, 3),
            gyro_bias_dps=rng.uniform(-GYRO_BIAS_MAX_DPS, GYRO_BIAS_MAX_DPS, 3),
            gyro_scale_error=rng.uniform(-0.01, 0.01, 3),
            gyro_misalignment=misalignment,
            gyro_g_sensitivity_per_g=GYRO_G_SENSITIVITY_PER_G
            * rng.uniform(0.95, 1.05, 3)
            * rng.choice([-1.0, 1.0], 3),
            gyro_noise_dps=GYRO_NOISE_DPS,
        )

    def to_dict(self) -> dict[str, Any]:
        """Every parameter as plain lists, plus the derived counts-to-g ``matrix``."""
        return {
            "offset_counts": self.offset_counts.tolist(),
            "sensitivity_counts_per_g": self.sensitivity_counts_per_g.tolist(),
            "cross_axis": self.cross_axis.tolist(),
            "matrix": self.matrix.tolist(),
            "noise_counts": self.noise_counts,
            "offset_tempco_counts_per_c": self.offset_tempco_counts_per_c.tolist(),
            "sensitivity_tempco_per_c": self.sensitivity_tempco_per_c.tolist(),
            "reference_temperature_c": REFERENCE_TEMPERATURE_C,
            "gyro_bias_dps": self.gyro_bias_dps.tolist(),
            "gyro_scale_error": self.gyro_scale_error.tolist(),
            "gyro_misalignment": self.gyro_misalignment.tolist(),
            "gyro_matrix": self.gyro_matrix.tolist(),
            "gyro_g_sensitivity_per_g": self.gyro_g_sensitivity_per_g.tolist(),
            "gyro_sense_axis": list(GYRO_SENSE_AXIS),
            "gyro_noise_dps": self.gyro_noise_dps,
        }


def accelerometer_counts(
    truth: SensorTruth,
    force_g: FloatArray,
    temperature_c: FloatArray,
    rng: np.random.Generator,
) -> FloatArray:
    """ADC counts (N-by-3, integers as float) for specific force ``force_g`` (N-by-3, g)."""
    dt = (temperature_c - REFERENCE_TEMPERATURE_C)[:, None]
    offset = truth.offset_counts + truth.offset_tempco_counts_per_c * dt
    sensitivity = truth.sensitivity_counts_per_g * (1 + truth.sensitivity_tempco_per_c * dt)
    analog = (
        offset
        + (force_g @ truth.cross_axis.T) * sensitivity
        + rng.normal(0.0, truth.noise_counts, force_g.shape)
    )
    return np.asarray(np.clip(np.rint(analog), ADC_MIN, truth.adc_max), dtype=np.float64)


def gyro_rates(
    truth: SensorTruth, rate_dps: FloatArray, force_g: FloatArray, rng: np.random.Generator
) -> FloatArray:
    """Measured rates (N-by-3, deg/s) for true body rates ``rate_dps`` ([Park2014]_ eq. 4)."""
    sense_force = force_g[:, list(GYRO_SENSE_AXIS)]
    return np.asarray(
        rate_dps
        + truth.gyro_bias_dps
        + rate_dps @ truth.gyro_misalignment.T
        + truth.gyro_scale_error * rate_dps
        + truth.gyro_g_sensitivity_per_g * sense_force * rate_dps
        + rng.normal(0.0, truth.gyro_noise_dps, rate_dps.shape),
        dtype=np.float64,
    )


@dataclass(frozen=True)
class Thermal:
    """Board temperature: ambient plus self-heating with a first-order time constant."""

    ambient_c: float = REFERENCE_TEMPERATURE_C
    self_heating_c: float = 1.5
    time_constant_s: float = 180.0

    def at(self, t: FloatArray) -> FloatArray:
        """Temperature (°C) at simulated times ``t`` (s since power-up)."""
        return self.ambient_c + self.self_heating_c * (1 - np.exp(-t / self.time_constant_s))
