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

Every declared quantity is checked against the data; a contradiction is a
:class:`StreamError`, one line naming what the stream reads and the declaration (or the
option) it contradicts:

- :func:`check_declared`, on the columns as read: a declared ``rate`` against the time
  column's own (when that column reads as time at all); an accelerometer declared in g or
  m/s² against gravity's magnitude at rest (1 g: 1 or 9.81; counts read hundreds);
- :func:`check_units`, on the stream in the station's units: an accelerometer in counts
  that reads about 1 or 9.8 at rest (g or m/s²) or whose gravity is no 1 g of the
  putter's counts; a time column whose steps make fewer than :data:`MIN_RATE_HZ` or more
  than :data:`MAX_RATE_HZ` samples a second (milliseconds, or seconds declared
  milliseconds); gyros whose largest rate is below :data:`MAX_RADS_PEAK` while the
  gravity direction turns by more than :data:`TURNED_DEG` (rad/s, not deg/s);
- :func:`check_turns`, on the moves between the still poses: how far the gyros turn
  against how far gravity turns between the two poses. A rotation by θ turns any
  direction by at most θ, so the angle a move's rates sweep is at least gravity's (a turn
  about the vertical adds to it); the median over the moves below :data:`MIN_TURN_RATIO`
  or above :data:`MAX_TURN_RATIO` (deg/s read as rad/s is 57 times too far) contradicts
  the gyro units.
"""

from dataclasses import dataclass, replace
from typing import Final, Literal

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.calibration.units import STANDARD_GRAVITY, AccelUnits, DeclaredUnits
from station.domain.gyro.motion.errors import StreamError
from station.domain.gyro.motion.integrate import step_rotvecs
from station.domain.gyro.motion.moves import Move
from station.domain.gyro.motion.stream import RecordedStream
from station.domain.sensors.sensor import NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G

GyroUnits = Literal["dps", "rads"]
#: How the results name each gyro unit.
GYRO_UNIT_NAMES: Final[dict[GyroUnits, str]] = {"dps": "deg/s", "rads": "rad/s"}
TimeUnits = Literal["s", "ms"]

#: Fewer samples a second than this is no IMU recording: the time column is not seconds.
MIN_RATE_HZ: Final = 5.0
#: A hand turns a putter at tens to hundreds of deg/s: a gyro peaking below this while the
#: unit turns reads rad/s.
MAX_RADS_PEAK: Final = 15.0
#: How far the gravity direction must turn over the recording for the gyro check to apply.
TURNED_DEG: Final = 45.0
#: More samples a second than this is no IMU's output (the fastest MEMS gyros give 32 kHz):
#: a time column in seconds read as milliseconds.
MAX_RATE_HZ: Final = 40_000.0
#: A declared rate and the time column's own that differ by more than this fraction
#: contradict each other.
RATE_TOLERANCE: Final = 0.1
#: Gravity at rest reads within this fraction of 1 g in the declared unit.
GRAVITY_TOLERANCE: Final = 0.3
#: Readings beyond this many g at rest are ADC counts, whatever was declared.
COUNTS_AT_REST_G: Final = 20.0
#: Moves whose gravity directions differ by less than this say nothing of the gyro units.
MIN_GRAVITY_TURN_DEG: Final = 20.0
#: The median move turns at least this fraction of gravity's turn (1 in theory; noise and
#: a move's ends averaged into its poses take a little).
MIN_TURN_RATIO: Final = 0.5
#: ... and at most this many times it (a hand's move adds a turn about the vertical, a few
#: times the tilt at most; deg/s read as rad/s is 57 times).
MAX_TURN_RATIO: Final = 10.0


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
    def gyro_name(self) -> str:
        """The gyro rates' unit as the results name it: ``deg/s`` or ``rad/s``."""
        return GYRO_UNIT_NAMES[self.gyro]

    def gyro_rate(self, dps: FloatArray) -> FloatArray:
        """Rates (a bias or its U) in deg/s, the station's unit, in the declared gyro unit."""
        return np.radians(dps) if self.gyro == "rads" else dps

    def restate_gyro(self, payload: dict[str, object]) -> dict[str, object]:
        """A stream's JSON (``StreamCalibration.to_dict``) with the gyro bias and its U in
        the declared gyro unit. Deg/s comes out unchanged (``gyro.bias_dps``,
        ``uncertainty.gyro_bias_dps``); rad/s under keys without the unit,
        ``gyro.bias`` and ``uncertainty.gyro_bias``, as the accelerometer's counts keys
        lose theirs in another unit (``DeclaredUnits.restate``). K is a ratio of rates
        and the moves' residuals angles: neither depends on the unit."""
        if self.gyro == "dps":
            return payload
        out = dict(payload)
        for section, key in (("gyro", "bias_dps"), ("uncertainty", "gyro_bias_dps")):
            part = out.get(section)
            if isinstance(part, dict) and key in part:
                restated = {k: v for k, v in part.items() if k != key}
                rates = self.gyro_rate(np.asarray(part[key], dtype=np.float64))
                restated[key.removesuffix("_dps")] = [float(v) for v in rates]
                out[section] = restated
        return out


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
    return replace(stream, t=t, accel_counts=accel, gyro_dps=gyro)


def _near(value: float, expected: float) -> bool:
    return abs(value / expected - 1.0) <= GRAVITY_TOLERANCE


def check_declared(raw: RecordedStream, units: StreamUnits) -> None:
    """Refuse a stream as read (before :func:`convert`) whose numbers contradict a declared
    rate or a declared accelerometer unit (module docstring), naming the declaration."""
    if units.rate_hz is not None:
        seconds = raw.t / 1000.0 if units.time == "ms" else raw.t
        own = float(1.0 / np.median(np.diff(seconds)))
        if MIN_RATE_HZ <= own <= MAX_RATE_HZ and abs(own / units.rate_hz - 1) > RATE_TOLERANCE:
            raise StreamError(
                f"stream: --rate {units.rate_hz:g} samples/s, but the time column steps "
                f"{1.0 / own:.4g} s ({own:.4g} samples/s): give that rate, or leave out --rate"
            )
    if units.accel == "counts":
        return
    shown = {"g": "g", "m/s2": "m/s²"}[units.accel]
    reads = float(np.median(np.linalg.norm(raw.accel_counts, axis=1)))
    per_g = units.accelerometer.per_g
    if _near(reads, per_g):
        return
    said = (
        f"stream: --accel-units {units.accel}, but the accelerometer reads {reads:.3g} "
        f"{shown} at rest"
    )
    if reads > COUNTS_AT_REST_G * per_g:
        raise StreamError(
            f"{said}: ADC counts? take off the sensor's zero, divide by its counts per g "
            "and use --accel-units g (the putter's own counts: --accel-units counts)"
        )
    for other, option, unit in ((1.0, "g", "g"), (STANDARD_GRAVITY, "m/s2", "m/s²")):
        if option != units.accel and _near(reads, other):
            raise StreamError(f"{said}: {unit}? use --accel-units {option}")
    raise StreamError(f"{said}, not 1 g ({per_g:g} {shown}): another unit, or a scale applied?")


def check_units(stream: RecordedStream, units: StreamUnits) -> None:
    """Refuse a stream (in the station's units, after :func:`convert`) whose numbers say
    its columns are in other units than ``units`` declares, saying which option fits."""
    rate = stream.rate_hz
    if units.rate_hz is None and not MIN_RATE_HZ <= rate <= MAX_RATE_HZ:
        unit, name = ("ms", "milliseconds") if rate < MIN_RATE_HZ else ("s", "seconds")
        hint = f"{name}? use --time-units {unit}, or" if units.time != unit else "so"
        raise StreamError(
            f"stream: time steps {1.0 / rate:.4g} s apart ({rate:.4g} samples/s): "
            f"{hint} give the rate with --rate HZ"
        )
    if units.accel == "counts":
        at_rest = float(np.median(np.linalg.norm(stream.accel_counts, axis=1)))
        for reads, unit, option in ((1.0, "g", "g"), (STANDARD_GRAVITY, "m/s²", "m/s2")):
            if _near(at_rest, reads):
                raise StreamError(
                    f"stream: accelerometer reads {at_rest:.3g} at rest: {unit}? use "
                    f"--accel-units {option}"
                )
        gravity = (
            float(np.median(np.linalg.norm(stream.accel_counts - units.zero_counts, axis=1)))
            / units.counts_per_g
        )
        if not _near(gravity, 1.0):
            raise StreamError(
                f"stream: accelerometer reads {gravity:.3g} g at rest in the putter's counts "
                f"(zero {units.zero_counts:g}, {units.counts_per_g:g} counts/g): another "
                "sensor's counts? convert them to g and use --accel-units g"
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


def check_turns(moves: list[Move], bias_dps: FloatArray, units: StreamUnits) -> None:
    """Refuse gyro units that the moves contradict: the median, over the moves whose
    gravity directions differ by :data:`MIN_GRAVITY_TURN_DEG` or more, of the angle the
    gyros (bias off) sweep over the move, Σ|φ_k| (the path's length on SO(3), never less
    than the net rotation's angle, and unlike it not folded at 180°), against the angle
    between those directions (module docstring)."""
    ratios = []
    for move in moves:
        tilt = move.gravity_turn_deg
        if tilt < MIN_GRAVITY_TURN_DEG or move.problem() is not None:
            continue
        steps = step_rotvecs(move.t, np.radians(move.rates_dps - bias_dps))
        ratios.append(float(np.degrees(np.linalg.norm(steps, axis=1).sum())) / tilt)
    if not ratios:
        return
    ratio = float(np.median(ratios))
    if MIN_TURN_RATIO <= ratio <= MAX_TURN_RATIO:
        return
    rate = "" if units.rate_hz is None else f" (or --rate {units.rate_hz:g} wrong)"
    said = (
        f"stream: the gyros turn {ratio:.3g} times as far as gravity turns between the "
        f"poses (median of {len(ratios)} moves)"
    )
    if units.gyro == "rads":
        hint = "deg/s? use --gyro-units dps" if ratio > MAX_TURN_RATIO else "not rad/s?"
        raise StreamError(f"{said}: --gyro-units rads, but {hint}{rate}")
    hint = (
        "rad/s? use --gyro-units rads"
        if ratio < MIN_TURN_RATIO
        else "not deg/s (raw counts?): convert them to deg/s or rad/s"
    )
    raise StreamError(f"{said}: {hint}{rate}")
