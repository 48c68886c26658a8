"""A whole recorded calibration stream: still poses, accelerometer, gyro bias and K.

The stream is the unit's raw output over the procedure of [Tedaldi2014]_: still poses
in varied orientations, with a hand move between each two. From it:

1. the still poses, by the station's own stillness judge
   (:func:`station.domain.signals.stillness.still_segments`) on windows fitted to the
   recording's rests (:func:`chosen_window`) or as given, with its limits fitted to the
   recording's own gyro bias and noise (:func:`adapted_thresholds`), each trimmed by a
   quarter window at both ends;
2. the accelerometer calibration from the poses' mean counts
   (:func:`station.domain.calibration.solve`, [Song2006]_);
3. the gyro bias, the mean rate over every still sample;
4. the moves between consecutive poses, with each pose's gravity direction
   ``u = C·(ā − o) / |C·(ā − o)|`` in the calibrated accelerometer's frame;
5. K from the moves (:func:`~station.domain.gyro.motion.matrix_fit.fit_gyro_matrix`),
   or the reason the moves cannot determine it (the rest is calibrated all the same).

Sample times come from ``t``; the sample rate is the inverse of the median step, and
each sample's sequence number is its time in median steps, so a gap counts against a
window's link loss as it does live.
"""

from collections.abc import Callable
from dataclasses import dataclass, field
from itertools import pairwise
from typing import Final

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.calibration import (
    UNKNOWNS,
    GeometryLimits,
    Model,
    Solution,
    Uncertainty,
    accelerometer_budget,
    apply,
    gyro_bias_uncertainty,
    gyro_matrix_uncertainty,
    solve,
)
from station.domain.calibration.uncertainty import (
    CROSS_AXIS_BOUND,
    OFFSET_TEMPCO_BOUND,
    SENSITIVITY_TEMPCO_BOUND,
)
from station.domain.constants import STILL_WINDOW_S
from station.domain.gyro.motion.errors import GyroMatrixError, StreamError
from station.domain.gyro.motion.matrix_fit import MIN_MOVES, GyroMatrixFit, fit_gyro_matrix
from station.domain.gyro.motion.moves import Move
from station.domain.sensors.sensor import AXES
from station.domain.signals.samples import SampleBlock
from station.domain.signals.stillness import (
    StillnessThresholds,
    StillSegment,
    still_segments,
    why_not_still,
)

#: Windows judged per still window (the hop is the window over this).
HOPS_PER_WINDOW: Final = 16
#: Each still segment loses this fraction of a window at both ends: a window that reaches
#: a little into a move can still pass (the start of a minimum-jerk turn is slow), and
#: the first tenth of a degree of the turn must be integrated, not averaged into the pose.
EDGE_TRIM: Final = 4
#: No MEMS gyro's bias reaches this (the MPU-6050's zero-rate output is within ±20 deg/s,
#: a fifth of this of its smallest range, ±250 deg/s): a still rate beyond it is an output's
#: zero not taken off, or the wrong units.
MAX_GYRO_BIAS_DPS: Final = 50.0


@dataclass(frozen=True, eq=False)
class RecordedStream:
    """Raw samples of a unit: times (s), accelerometer (ADC counts), gyros (deg/s); the
    sensor's temperature (°C) when the recording has it."""

    t: FloatArray
    accel_counts: FloatArray
    gyro_dps: FloatArray
    temperature_c: FloatArray | None = None

    def __post_init__(self) -> None:
        n = len(self.t)
        if self.t.shape != (n,) or self.accel_counts.shape != (n, 3):
            raise StreamError(f"stream: t must be (n,) and accel (n, 3), got {self.t.shape}")
        if self.gyro_dps.shape != (n, 3):
            raise StreamError(f"stream: gyro must be ({n}, 3), got {self.gyro_dps.shape}")
        if self.temperature_c is not None and self.temperature_c.shape != (n,):
            raise StreamError(f"stream: temperature must be ({n},)")
        columns = (self.t, self.accel_counts, self.gyro_dps, self.temperature_c)
        if not all(np.isfinite(c).all() for c in columns if c is not None):
            raise StreamError("stream: a value is not a finite number")
        if n < 2:
            raise StreamError(f"stream: {n} samples, too few to calibrate from")
        step = np.diff(self.t)
        if (step <= 0).any():
            k = int(np.argmax(step <= 0)) + 1
            raise StreamError(
                f"stream: t does not increase at data row {k + 1} (t = {self.t[k]:.6g})"
            )

    @property
    def rate_hz(self) -> float:
        """Samples per second: the inverse of the median time step."""
        return float(1.0 / np.median(np.diff(self.t)))

    def block(self) -> SampleBlock:
        """The samples as the station's blocks: sequence numbers from ``t``, no temperature."""
        seq = np.rint((self.t - self.t[0]) * self.rate_hz)
        return SampleBlock.from_columns(seq, self.accel_counts, self.gyro_dps, np.zeros(len(seq)))


@dataclass(frozen=True, eq=False)
class StreamCalibration:
    """Everything fitted from one stream.

    Attributes:
        stills: the still segments (rows of the stream), in order.
        accel: the accelerometer calibration from the stills' mean counts.
        gravity: shape (stills, 3), each still's gravity direction, calibrated frame.
        bias_dps: shape (3,), mean gyro rate over all still samples, deg/s.
        moves: the moves between consecutive stills.
        gyro: K fitted from the moves, or None when they cannot determine it.
        uncertainty: expanded uncertainties (k = 2) of the accelerometer's coefficients,
            the gyro bias and K (:mod:`station.domain.calibration.uncertainty`).
        gyro_not_determined: why the moves cannot determine K (too few usable ones, or
            about too few axes), when they cannot; the accelerometer and the gyro bias
            are calibrated all the same.
        still_window_s: the still window the poses were found with, seconds.
        temperatures: shape (stills,), each still's mean temperature, °C (None when the
            recording has none).
        excluded_influences: the influences not in U, by name
            (:data:`~station.domain.calibration.uncertainty.EXCLUDED_WHY`).
        disturbed: the stills (from 0) whose spread is well above the noise, de-weighted
            in U, each with its spread over the noise
            (:attr:`~station.domain.calibration.uncertainty.AccelerometerBudget.disturbed`).
    """

    stills: list[StillSegment]
    accel: Solution
    gravity: FloatArray
    bias_dps: FloatArray
    moves: list[Move]
    gyro: GyroMatrixFit | None
    uncertainty: Uncertainty
    gyro_not_determined: str | None = None
    still_window_s: float | None = None
    temperatures: FloatArray | None = None
    excluded_influences: tuple[str, ...] = ()
    disturbed: dict[int, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: the accelerometer's keys, ``poses`` and ``gyro`` (K's keys null and
        ``not_determined`` the reason, when the moves cannot determine K)."""
        payload = self.accel.to_dict()
        payload["poses"] = len(self.stills)
        payload["still_window_s"] = self.still_window_s
        if self.gyro is not None:
            payload["gyro"] = self.gyro.to_dict() | {"not_determined": None}
        else:
            payload["gyro"] = {
                "bias_dps": self.bias_dps.tolist(),
                "scale_matrix": None,
                "scale_matrix_standard_errors": None,
                "moves": len(self.moves),
                "not_determined": self.gyro_not_determined,
            }
        payload["uncertainty"] = self.uncertainty.to_dict()
        payload["disturbed_poses"] = [
            {"pose": pose + 1, "spread_over_noise": ratio} for pose, ratio in self.disturbed.items()
        ]
        return payload


def stream_thresholds(
    rate_hz: float, still_window_s: float = STILL_WINDOW_S
) -> StillnessThresholds:
    """The live stillness limits with the window set to ``still_window_s`` at ``rate_hz``."""
    width = max(16, round(still_window_s * rate_hz))
    return StillnessThresholds(window_samples=width, hop_samples=max(1, width // HOPS_PER_WINDOW))


#: A recording's spread limits never fall below the live ones; they rise to this many
#: times its own quiet spread (an IMU noisier than the putter's).
NOISE_MARGIN: Final = 4.0


def _window_stats(values: FloatArray, width: int, hop: int) -> tuple[FloatArray, FloatArray]:
    """Means and standard deviations of ``values`` (n, 3) over windows of ``width`` rows
    every ``hop`` rows: running sums, linear in the rows whatever the window."""
    starts = np.arange(0, len(values) - width + 1, hop)
    zero = np.zeros((1, values.shape[1]))
    s1 = np.concatenate((zero, np.cumsum(values, axis=0)))
    s2 = np.concatenate((zero, np.cumsum(values * values, axis=0)))
    total = s1[starts + width] - s1[starts]
    squares = s2[starts + width] - s2[starts]
    mean = total / width
    var = np.maximum(squares / width - mean * mean, 0.0) * width / (width - 1)
    return mean, np.sqrt(var)


def adapted_thresholds(stream: RecordedStream, limits: StillnessThresholds) -> StillnessThresholds:
    """The stillness limits fitted to the recording's own gyro bias and noise.

    A recording is mostly still poses, so its quieter windows are the unit at rest: the
    windows whose largest accelerometer spread is at most the median of all windows',
    and of those, the ones whose largest gyro spread is at most their median. Their
    median gyro rate is each gyro's bias, taken off before a rate is judged (a MEMS
    gyro's bias of several deg/s would otherwise make every window "turn"); the spread
    limits rise to :data:`NOISE_MARGIN` times their median spread where that is above
    the live limits (a noisier IMU than the putter's), never below.
    """
    width, hop = limits.window_samples, limits.hop_samples
    if len(stream.t) < width:
        return limits
    _, accel_std = _window_stats(stream.accel_counts, width, hop)
    gyro_mean, gyro_std = _window_stats(stream.gyro_dps, width, hop)
    accel_score, gyro_score = accel_std.max(axis=1), gyro_std.max(axis=1)
    calm = accel_score <= np.median(accel_score)
    quiet = calm & (gyro_score <= np.median(gyro_score[calm]))
    return limits.model_copy(
        update={
            "gyro_bias_dps": tuple(float(b) for b in np.median(gyro_mean[quiet], axis=0)),
            "accel_std_max_counts": max(
                limits.accel_std_max_counts,
                NOISE_MARGIN * float(np.median(accel_std[quiet], axis=0).max()),
            ),
            "gyro_std_max_dps": max(
                limits.gyro_std_max_dps,
                NOISE_MARGIN * float(np.median(gyro_std[quiet], axis=0).max()),
            ),
        }
    )


#: The still window the rests are first looked for with, seconds (and never under the
#: judge's 16 samples).
PROBE_WINDOW_S: Final = 0.25
#: The shortest still window chosen, seconds: a hand's rest of a second holds one; a
#: shorter one lets a rate that swings slowly through zero pass for a rest.
MIN_WINDOW_S: Final = 0.5
#: The chosen window is this fraction of the rest it must still fit in: a window starts
#: every 1/16 of itself, so one of half a rest's length always lies wholly inside it.
REST_FRACTION: Final = 0.5


def chosen_window(stream: RecordedStream, model: Model) -> StillnessThresholds:
    """The still window fitted to the recording's own rests and noise.

    The rests are first found with a short probe window (:data:`PROBE_WINDOW_S`) under
    limits fitted to the recording's noise and gyro bias (:func:`adapted_thresholds`).
    The window is then :data:`REST_FRACTION` of the k-th longest rest, k the poses K
    needs (``MIN_MOVES + 1``, at least the model's poses; the model's poses when fewer
    rests are found), between :data:`MIN_WINDOW_S` and :data:`STILL_WINDOW_S` (the
    shortest when fewer rests than the model's poses are found): the k longest rests
    keep a whole window each, shorter fragments of a rest that a knock split (what a short
    window takes for many "poses") fall away, and a recording whose rests last twice the
    default second or more is judged on the default window.
    """
    probe = stream_thresholds(stream.rate_hz, PROBE_WINDOW_S)
    rests = still_segments(stream.block(), adapted_thresholds(stream, probe))
    needed = UNKNOWNS[model]
    if len(rests) < needed:
        return stream_thresholds(stream.rate_hz, MIN_WINDOW_S)
    lengths = sorted((len(r) for r in rests), reverse=True)
    kth = lengths[min(max(needed, MIN_MOVES + 1), len(lengths)) - 1]
    seconds = REST_FRACTION * kth / stream.rate_hz
    return stream_thresholds(stream.rate_hz, min(max(seconds, MIN_WINDOW_S), STILL_WINDOW_S))


def calibrate_stream(
    stream: RecordedStream,
    model: Model = "nine",
    *,
    thresholds: StillnessThresholds | None = None,
    min_moves: int = MIN_MOVES,
    known_turn_deg: float | None = None,
    check_moves: Callable[[list[Move], FloatArray], None] | None = None,
    tempco: tuple[float, float] = (OFFSET_TEMPCO_BOUND, SENSITIVITY_TEMPCO_BOUND),
    cross_axis_bound: float = CROSS_AXIS_BOUND,
    gyro_bias_repeatability_dps: float | FloatArray | None = None,
) -> StreamCalibration:
    """Find the stills, fit the accelerometer, the gyro bias and K (module docstring).

    ``thresholds``: the stillness limits and window; None: the window fitted to the
    recording's rests (:func:`chosen_window`). ``min_moves`` and ``known_turn_deg`` (the
    angle of the recording's whole turns, when it declares one) go to
    :func:`~station.domain.gyro.motion.matrix_fit.fit_gyro_matrix`.
    ``check_moves(moves, bias_dps)``, when given, may refuse the moves before K is fitted
    (:func:`station.domain.gyro.motion.stream_units.check_turns`). ``tempco``: the
    sensor's temperature coefficients' half-widths (counts/°C, /°C) for the budget's
    temperature term, when the stream has a temperature; ``cross_axis_bound``: its
    cross-axis sensitivity, the six-parameter model's unmodelled coupling;
    ``gyro_bias_repeatability_dps``: its gyros' turn-on to turn-on bias repeatability,
    declared or measured across sessions, one figure or one per axis (None: neither,
    named as excluded from U).

    Raises:
        StreamError: fewer still poses than ``model`` needs; a gyro bias beyond
            :data:`MAX_GYRO_BIAS_DPS`; what ``check_moves`` raises.
        station.domain.calibration.CalibrationError: the poses cannot calibrate the accelerometer.
    """
    limits = adapted_thresholds(stream, thresholds or chosen_window(stream, model))
    trim = limits.window_samples // EDGE_TRIM
    stills = [
        StillSegment(s.start + trim, s.stop - trim) for s in still_segments(stream.block(), limits)
    ]
    needed = UNKNOWNS[model]
    if len(stills) < needed:
        why = why_not_still(stream.block(), limits)
        raise StreamError(
            f"stream: {len(stills)} still poses found, the {model}-parameter model needs "
            f"{needed} (still window {limits.window_samples} samples)"
            + (f"; windows not still: {why}" if why else "")
        )
    means = np.array([stream.accel_counts[s.start : s.stop].mean(axis=0) for s in stills])
    spreads = np.array([stream.accel_counts[s.start : s.stop].std(axis=0, ddof=1) for s in stills])
    samples = np.array([len(s) for s in stills])
    # Near-duplicate poses refuse only the six-pose eq. 10: a recorded procedure often
    # returns to an orientation it held before, and least squares is not degenerate for it
    # (each pose is one more equation), eq. 10 with six is.
    paper = model == "six" and len(means) == UNKNOWNS["six"]
    accel = solve(means, model, GeometryLimits() if paper else GeometryLimits(min_angle_deg=0.0))
    g = apply(accel.calibration, means)
    gravity = g / np.linalg.norm(g, axis=1, keepdims=True)
    still_gyro = np.concatenate([stream.gyro_dps[s.start : s.stop] for s in stills])
    bias = still_gyro.mean(axis=0)
    # Each move from the last sample of a still to the first of the next.
    spans = [slice(a.stop - 1, b.start + 1) for a, b in pairwise(stills)]
    moves = [
        Move(stream.t[s], stream.gyro_dps[s], gravity[i], gravity[i + 1])
        for i, s in enumerate(spans)
    ]
    if check_moves is not None:
        check_moves(moves, bias)
    beyond = np.flatnonzero(np.abs(bias) > MAX_GYRO_BIAS_DPS)
    if len(beyond):
        axis = AXES[int(beyond[0])]
        raise StreamError(
            f"stream: gyro {axis} reads {bias[beyond[0]]:+.4g} deg/s at rest, beyond the "
            f"{MAX_GYRO_BIAS_DPS:g} deg/s a MEMS gyro's bias reaches: an output's zero not "
            "taken off (32768 of a 16-bit one?), or the gyro units"
        )
    gyro: GyroMatrixFit | None = None
    not_determined = None
    try:
        gyro = fit_gyro_matrix(moves, bias, min_moves=min_moves, known_turn_deg=known_turn_deg)
    except GyroMatrixError as exc:
        not_determined = str(exc)
    # Least squares over the moves alone can do no worse than K = I, which it may choose;
    # a K that does worse was pulled off by something else (declared turns the moves
    # contradict) or stopped in a false minimum, and is no calibration.
    if gyro is not None and gyro.residual_rms_deg > gyro.residual_identity_rms_deg:
        not_determined = (
            f"K fitted to the {len(gyro.used)} moves leaves them {gyro.residual_rms_deg:.3g}° "
            f"RMS off, more than without it ({gyro.residual_identity_rms_deg:.3g}° with K = I): "
            "the moves do not determine it (poses split from one rest, or declared turns they "
            "contradict?)"
        )
        gyro = None
    gyro_means = np.array([stream.gyro_dps[s.start : s.stop].mean(axis=0) for s in stills])
    gyro_spreads = np.array([stream.gyro_dps[s.start : s.stop].std(axis=0, ddof=1) for s in stills])
    temperatures = (
        None
        if stream.temperature_c is None
        else np.array([stream.temperature_c[s.start : s.stop].mean() for s in stills])
    )
    budget = accelerometer_budget(
        accel,
        means,
        spreads,
        samples,
        temperatures=temperatures,
        tempco=tempco,
        cross_axis_bound=cross_axis_bound,
    )
    repeatability = 0.0 if gyro_bias_repeatability_dps is None else gyro_bias_repeatability_dps
    uncertainty = Uncertainty.of_budget(budget).with_gyro(
        gyro_bias_uncertainty(gyro_means, gyro_spreads, samples, repeatability_dps=repeatability),
        None if gyro is None else gyro_matrix_uncertainty(gyro, budget),
    )
    return StreamCalibration(
        stills=stills,
        accel=accel,
        gravity=gravity,
        bias_dps=bias,
        moves=moves,
        gyro=gyro,
        uncertainty=uncertainty,
        gyro_not_determined=not_determined,
        still_window_s=limits.window_samples / stream.rate_hz,
        temperatures=temperatures,
        excluded_influences=budget.excluded_influences
        + (() if gyro_bias_repeatability_dps is not None else ("gyro_bias_repeatability",)),
        disturbed=budget.disturbed,
    )
