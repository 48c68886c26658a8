"""Judging still windows, live or recorded: one judge for both.

The accelerometer cannot tell motion from gravity, so a pose is recorded only from a
window in which the unit demonstrably did not move ([Song2006]_: at rest). A window of
``window_samples`` consecutive samples is accepted when all of these hold:

- spread: every accelerometer axis' standard deviation is small (handling, tremor);
- drift: the mean of the window's last quarter is close to that of its first quarter
  on every axis (slow tilting that the spread alone would let through);
- gravity: ``|a|``, with nominal offset and sensitivity, is near 1 g (free fall, a
  steady push, a dead axis);
- rotation: the gyros' mean rates and their spread are small (turning about the
  vertical changes no accelerometer reading at all: only the gyro sees it);
- link: few samples are missing in the window, and no axis sits at an ADC rail.

Live, :class:`station.run.acquisition.StillnessDetector` evaluates the trailing
window every ``hop_samples`` samples, so a unit that is still from the start is accepted
after at most ``window + hop`` samples. Recorded, :func:`still_segments` judges the
windows starting every ``hop_samples`` rows of a whole stream and merges the still ones
that overlap into still segments (the poses of a recorded calibration).
"""

import math
import re
from collections import Counter
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from station.domain.arrays import FloatArray
from station.domain.sensors.sensor import ADC_MIN, AXES, SAMPLES_PER_POSE
from station.domain.sensors.sensor_spec import PUTTER_SENSOR, SensorSpec
from station.domain.signals.samples import SampleBlock, WindowSummary

#: A hand moving or a tremor shows as a spread of 5 mg and more: a still window's spread
#: stays below 4.9 mg (4 counts of the putter's 819.2 counts/g) ...
MOTION_SPREAD_G: Final = 0.0048828125
#: ... and, on a noisier sensor, below 4 times its white noise (4 counts of the
#: putter's 1 count rms: the two bounds agree on it).
MOTION_SPREAD_NOISES: Final = 4.0
#: A window's first-to-last-quarter change of an axis' mean: 2.4 mg is 0.14 degree of
#: tilt (2 counts of the putter).
DRIFT_G: Final = 0.00244140625


def spread_limit_counts(sensor: SensorSpec) -> float:
    """The largest per-axis spread of a still window in ``sensor``'s counts: the motion
    bound in g or four times the sensor's noise, whichever is larger."""
    return sensor.counts(max(MOTION_SPREAD_G, MOTION_SPREAD_NOISES * sensor.noise_g))


def drift_limit_counts(sensor: SensorSpec) -> float:
    """The largest drift of a still window's mean in ``sensor``'s counts."""
    return sensor.counts(DRIFT_G)


class StillnessThresholds(BaseModel):
    """Limits a window must meet to count as still; defaults with their reasons.

    The accelerometer's limits are in the counts of ``sensor`` (the product's, set by the
    station's configuration): those not given are derived from it
    (:func:`spread_limit_counts`, :func:`drift_limit_counts`); its rails and nominal
    zero g and sensitivity judge saturation and gravity.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    sensor: SensorSpec = Field(
        PUTTER_SENSOR,
        description="the product's sensor, whose counts the window is in (set from the "
        "station's product, station.domain.product.products)",
    )

    window_samples: int = Field(
        SAMPLES_PER_POSE,
        ge=16,
        description="samples per still window: 1024, as the paper averages per pose",
    )
    hop_samples: int = Field(
        32,
        ge=1,
        description="samples between evaluations: 3 % of a window, well inside the "
        "10 % acceptance-latency budget, and 32 times less work than every sample",
    )
    accel_std_max_counts: float = Field(
        spread_limit_counts(PUTTER_SENSOR),
        gt=0,
        description="per-axis spread: a hand moving or a tremor of 5 mg and more shows as "
        "4.9 mg (4 counts of the putter, whose noise is ~1 count, 1.2 mg, rms); at least 4 "
        "times the sensor's noise; default: the sensor's (spread_limit_counts)",
    )
    accel_drift_max_counts: float = Field(
        drift_limit_counts(PUTTER_SENSOR),
        gt=0,
        description="first-to-last-quarter change of an axis' mean: 2.4 mg (2 counts of "
        "the putter) is 0.14 degree of tilt and moves the window's mean by under 0.1 % of "
        "the sensitivity; noise contributes 0.1 count; default: the sensor's "
        "(drift_limit_counts)",
    )
    gravity_tolerance_g: float = Field(
        0.5,
        gt=0,
        description="|a| with nominal scaling may differ from 1 g by offset and "
        "sensitivity errors before calibration: up to 207 counts (0.25 g) on each axis, "
        "0.44 g when all three sit at the same extreme, plus 5 % of sensitivity; beyond "
        "0.5 g the unit is accelerating, falling or an axis is dead",
    )
    gyro_rate_max_dps: float = Field(
        1.0,
        gt=0,
        description="mean rate per gyro: above the uncalibrated bias (0.3 deg/s) with "
        "margin, while a turn of 1 deg/s (2 degrees over a window) is refused",
    )
    gyro_std_max_dps: float = Field(
        0.5,
        gt=0,
        description="per-gyro spread: white noise is under 0.1 deg/s rms; handling and "
        "tremor rates are several deg/s",
    )
    gyro_bias_dps: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0),
        description="each gyro's bias, taken off its mean rate before the rate is judged: "
        "0 live (the putter's gyros are within 0.3 deg/s); a recording's own, estimated "
        "from its quietest windows (station.domain.gyro.motion.stream.adapted_thresholds)",
    )
    max_loss_fraction: float = Field(
        0.01,
        ge=0,
        le=1,
        description="samples missing from the window: above 1 % the link is too bad to "
        "trust the window's statistics",
    )

    @model_validator(mode="before")
    @classmethod
    def _in_the_sensors_counts(cls, data: Any) -> Any:
        """The accelerometer limits not given, in the given sensor's counts."""
        if not isinstance(data, dict) or "sensor" not in data:
            return data
        sensor = SensorSpec.model_validate(data["sensor"])
        return {
            "accel_std_max_counts": spread_limit_counts(sensor),
            "accel_drift_max_counts": drift_limit_counts(sensor),
            **data,
        }


@dataclass(frozen=True)
class WindowVerdict:
    """How one window fared: the reasons it was refused (empty when still)."""

    reasons: tuple[str, ...]
    saturated_axes: tuple[str, ...]
    loss_fraction: float
    motion: bool
    window: SampleBlock
    #: The window's means and spreads (sample standard deviations), as judged.
    summary: WindowSummary

    @property
    def still(self) -> bool:
        """True when nothing refused the window."""
        return not self.reasons


def judge_window(block: SampleBlock, limits: StillnessThresholds) -> WindowVerdict:
    """Judge one window of samples.

    Spreads are the window's sample standard deviations (:meth:`SampleBlock.summary`).
    """
    acc = block.accel
    summary = block.summary()
    sensor = limits.sensor
    reasons: list[str] = []
    span = block.span
    loss = 1.0 - len(block) / span if span > 0 else 0.0
    if loss > limits.max_loss_fraction:
        reasons.append(f"link lost {loss:.1%} of samples > {limits.max_loss_fraction:.1%}")
    # Whole-array operations, then plain floats per axis: the live view judges a window
    # at every pass per slot, and numpy's per-call overhead is most of the cost.
    at_rail = np.any((acc <= ADC_MIN) | (acc >= sensor.adc_max), axis=0).tolist()
    saturated = tuple(axis for axis, rail in zip(AXES, at_rail, strict=True) if rail)
    if saturated:
        reasons.append(f"accel {', '.join(saturated)} at the ADC rail")
    unmoved = len(reasons)  # the link's and the rails' reasons: every later one is motion
    quarter = max(1, len(block) // 4)
    firsts, lasts = acc[:quarter].sum(axis=0).tolist(), acc[-quarter:].sum(axis=0).tolist()
    spread_max, drift_max = limits.accel_std_max_counts, limits.accel_drift_max_counts
    spreads = summary.accel_std.tolist()
    for axis, s, first, last in zip(AXES, spreads, firsts, lasts, strict=True):
        if axis in saturated:
            continue
        if s > spread_max:
            reasons.append(f"accel {axis} spread {s:.1f} counts > {spread_max:g}")
        if (drift := abs(last / quarter - first / quarter)) > drift_max:
            reasons.append(f"accel {axis} drifted {drift:.1f} counts > {drift_max:g}")
    nominal_g = (summary.accel_mean - sensor.zero_g_counts) / sensor.counts_per_g
    magnitude = math.sqrt(float(nominal_g @ nominal_g))
    if not saturated and abs(magnitude - 1.0) > limits.gravity_tolerance_g:
        reasons.append(f"|a| {magnitude:.2f} g is not 1 g ± {limits.gravity_tolerance_g:g}")
    rate_max, gyro_spread_max = limits.gyro_rate_max_dps, limits.gyro_std_max_dps
    rates = zip(summary.gyro_mean.tolist(), limits.gyro_bias_dps, strict=True)
    for axis, (mean, bias), s in zip(AXES, rates, summary.gyro_std.tolist(), strict=True):
        if abs(rate := mean - bias) > rate_max:
            reasons.append(f"gyro {axis} turning {rate:+.2f} deg/s > {rate_max:g}")
        if s > gyro_spread_max:
            reasons.append(f"gyro {axis} spread {s:.2f} deg/s > {gyro_spread_max:g}")
    motion = len(reasons) > unmoved
    return WindowVerdict(tuple(reasons), saturated, loss, motion, block, summary)


class SpreadScreen:
    """Which windows of a block of counts the judge would certainly refuse for an
    accelerometer spread above ``limit`` (a cheap screen, for windows whose verdict nobody
    reads: the live detector keeps only its latest one).

    From running sums of the counts and their squares, exact in integers, a window's
    sample variance is (n·Σx² − (Σx)²) / (n(n − 1)) with no rounding at all; a window is
    screened out only when that exceeds the limit's square by a relative margin far above
    the judge's own rounding (~1e-13), so the judge, which sees the same spread, refuses
    it too. Axes with a sample at an ADC rail are left out, as the judge leaves them out.
    A block that is not whole counts (a calibrated stream) screens nothing.
    """

    #: Relative margin over the limit's square: the judge's float spread is within ~1e-13.
    MARGIN: Final = 1e-9

    def __init__(self, accel: FloatArray, limit: float, adc_max: int) -> None:
        counts = accel.astype(np.int64)
        self._whole = bool(np.array_equal(counts, accel))
        zero = np.zeros((1, 3), dtype=np.int64)
        self._sums = np.concatenate((zero, counts.cumsum(axis=0)))
        self._squares = np.concatenate((zero, (counts * counts).cumsum(axis=0)))
        rail = (counts <= ADC_MIN) | (counts >= adc_max)
        self._rails = np.concatenate((zero, rail.cumsum(axis=0)))
        self._bound = limit * limit * (1.0 + self.MARGIN)

    def refuses(self, start: int, stop: int) -> bool:
        """Whether rows ``start`` to ``stop`` (excluded) certainly spread too much."""
        n = stop - start
        if not self._whole or n < 2:
            return False
        total = self._sums[stop] - self._sums[start]
        squares = self._squares[stop] - self._squares[start]
        free = (self._rails[stop] - self._rails[start]) == 0
        excess = (n * squares - total * total)[free]
        return bool(np.any(excess > self._bound * (n * (n - 1))))


@dataclass(frozen=True)
class StillSegment:
    """Rows ``start`` (included) to ``stop`` (excluded) of a recorded stream, all still."""

    start: int
    stop: int

    def __len__(self) -> int:
        return self.stop - self.start


def still_segments(block: SampleBlock, limits: StillnessThresholds) -> list[StillSegment]:
    """The still segments of a recorded stream, in order.

    Every window of ``window_samples`` rows starting at a multiple of ``hop_samples``
    is judged by :func:`judge_window` (the live judge); still windows that overlap
    merge into one segment (two that only touch stay apart: a refused window lies
    between them). A gap in the sequence numbers counts against a
    window's link loss just as live. Work and memory grow linearly with the rows.
    """
    width, hop = limits.window_samples, limits.hop_samples
    segments: list[StillSegment] = []
    for start in range(0, len(block) - width + 1, hop):
        if not judge_window(block[start : start + width], limits).still:
            continue
        if segments and start < segments[-1].stop:
            segments[-1] = StillSegment(segments[-1].start, start + width)
        else:
            segments.append(StillSegment(start, start + width))
    return segments


#: A refused window's reason without its numbers: what kind of refusal it is.
_NUMBERS = re.compile(r"[-+]?\d[\d.]*%?")
_OTHER_COUNTS = (
    "the accelerometer not in this putter's counts (zero 2048, 819.2 counts/g)? "
    "declare --accel-units"
)
#: What each kind of refusal, in most windows of a recording, says about it.
_HINTS = (
    ("turning", "a unit never at rest, a gyro's rate swinging, or gyro units not deg/s?"),
    ("at the ADC rail", _OTHER_COUNTS),
    ("is not 1 g", _OTHER_COUNTS),
    ("spread", "more noise than the stillness limits allow, or the unit never held still?"),
)


def why_not_still(block: SampleBlock, limits: StillnessThresholds) -> str:
    """Why the windows of a recording were refused, in words: how many, the commonest
    reason (with one window's numbers) and, when that reason refused most of them, what
    it likely means. Empty when every window was still (or there is none)."""
    width, hop = limits.window_samples, limits.hop_samples
    kinds: Counter[str] = Counter()
    example: dict[str, str] = {}
    windows = 0
    for start in range(0, len(block) - width + 1, hop):
        windows += 1
        for reason in judge_window(block[start : start + width], limits).reasons:
            kind = _NUMBERS.sub("#", reason)
            kinds[kind] += 1
            example.setdefault(kind, reason)
    if not kinds:
        return ""
    kind, count = kinds.most_common(1)[0]
    words = f"most often {example[kind]} ({count} of {windows} windows)"
    if count >= 0.9 * windows:
        hint = next((h for key, h in _HINTS if key in kind), None)
        if hint is not None:
            words += f": {hint}"
    return words
