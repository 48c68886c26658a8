"""A recorded stream's declared units, converted to the station's, and the checks that a
stream read in the station's units looks like them.

The station computes in ADC counts (the putter's: zero 2048, 819.2 counts/g, [Song2006]_
Table 1), deg/s and seconds. Another IMU's recording declares its own:

- accelerometer ``counts`` (as is), ``g`` (``a → zero + a·counts_per_g``) or ``m/s2``
  (``a → zero + a/g₀·counts_per_g``, g₀ = 9.80665 m/s², the standard gravity that
  defines the unit g);
- gyro ``dps`` or ``rads`` (``ω → ω·180/π``);
- time ``s`` or ``ms`` (``t → t/1000``), or a sample ``rate`` (``t → i/rate``: the time
  column is then ignored).

The checks (:func:`check_units`) catch the common mistakes in the operator's terms, each
a :class:`StreamError` naming what the stream reads and the option that fits it: an
accelerometer that reads about 1 or 9.8 at rest (in g or m/s², not counts); a time
column whose steps make fewer than :data:`MIN_RATE_HZ` samples a second (milliseconds);
gyros whose largest rate is below :data:`MAX_RADS_PEAK` while the gravity direction turns
by more than :data:`TURNED_DEG` (rad/s, not deg/s).
"""

from dataclasses import dataclass
from typing import Final, Literal

import numpy as np

from station.domain.calibration.units import STANDARD_GRAVITY, AccelUnits, DeclaredUnits
from station.domain.gyro.motion.errors import StreamError
from station.domain.gyro.motion.stream import RecordedStream
from station.domain.sensor import NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G

GyroUnits = Literal["dps", "rads"]
TimeUnits = Literal["s", "ms"]

#: Fewer samples a second than this is no IMU recording: the time column is not seconds.
MIN_RATE_HZ: Final = 5.0
#: A hand turns a putter at tens to hundreds of deg/s: a gyro peaking below this while the
#: unit turns reads rad/s.
MAX_RADS_PEAK: Final = 15.0
#: How far the gravity direction must turn over the recording for the gyro check to apply.
TURNED_DEG: Final = 45.0


@dataclass(frozen=True)
class StreamUnits:
    """What the columns of a recording are in (module docstring)."""

    accel: AccelUnits = "counts"
    gyro: GyroUnits = "dps"
    time: TimeUnits = "s"
    rate_hz: float | None = None
    zero_counts: float = NOMINAL_OFFSET_COUNTS
    counts_per_g: float = NOMINAL_SENSITIVITY_COUNTS_PER_G

    def __post_init__(self) -> None:
        if self.rate_hz is not None and not (0.0 < self.rate_hz < float("inf")):
            raise StreamError(f"stream: rate {self.rate_hz:g} samples/s is not a positive rate")

    @property
    def accelerometer(self) -> DeclaredUnits:
        """The accelerometer's declared unit, which its results are stated in."""
        return DeclaredUnits(self.accel, self.zero_counts, self.counts_per_g)

    @property
    def declared(self) -> bool:
        """Whether anything but the station's own units was declared."""
        return self != StreamUnits()


def convert(stream: RecordedStream, units: StreamUnits) -> RecordedStream:
    """``stream`` as read (its columns in ``units``) in counts, deg/s and seconds."""
    accel = units.accelerometer.to_counts(stream.accel_counts)
    gyro = np.degrees(stream.gyro_dps) if units.gyro == "rads" else stream.gyro_dps
    if units.rate_hz is not None:
        t = np.arange(len(stream.t), dtype=np.float64) / units.rate_hz
    elif units.time == "ms":
        t = stream.t / 1000.0
    else:
        t = stream.t
    return RecordedStream(t=t, accel_counts=accel, gyro_dps=gyro)


def check_units(stream: RecordedStream, units: StreamUnits) -> None:
    """Refuse a stream (in the station's units, after :func:`convert`) whose numbers say
    its columns are in other units than ``units`` declares, saying which option fits."""
    rate = stream.rate_hz
    if units.rate_hz is None and rate < MIN_RATE_HZ:
        hint = "milliseconds? use --time-units ms, or" if units.time == "s" else "so"
        raise StreamError(
            f"stream: time steps {1.0 / rate:.4g} s apart ({rate:.4g} samples/s): "
            f"{hint} give the rate with --rate HZ"
        )
    if units.accel == "counts":
        at_rest = float(np.median(np.linalg.norm(stream.accel_counts, axis=1)))
        for reads, unit, option in ((1.0, "g", "g"), (STANDARD_GRAVITY, "m/s²", "m/s2")):
            if 0.7 * reads <= at_rest <= 1.3 * reads:
                raise StreamError(
                    f"stream: accelerometer reads {at_rest:.3g} at rest: {unit}? use "
                    f"--accel-units {option}"
                )
    if units.gyro == "dps":
        peak = float(np.max(np.abs(stream.gyro_dps)))
        turned = _turned_deg(stream.accel_counts - units.zero_counts)
        if peak < MAX_RADS_PEAK and turned > TURNED_DEG:
            raise StreamError(
                f"stream: gyro peaks at {peak:.3g} deg/s while gravity turns by {turned:.0f}°: "
                "rad/s? use --gyro-units rads"
            )


def _turned_deg(accel: np.ndarray) -> float:
    """The largest angle between the accelerometer's direction and its first, degrees."""
    norms = np.linalg.norm(accel, axis=1)
    usable = norms > 0
    if not usable.any():
        return 0.0
    directions = accel[usable] / norms[usable, None]
    cosines = np.clip(directions @ directions[0], -1.0, 1.0)
    return float(np.degrees(np.arccos(cosines.min())))
