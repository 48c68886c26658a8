"""The run's count thresholds follow the product's sensor (station.domain.sensors.sensor_spec):
physical bounds in g times its counts per g, noise bounds its noise, rails its ADC."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.domain.calibration.geometry import (
    Finding,
    GeometryLimits,
    datasheet_reach_counts,
    rail_margin_counts,
    screen,
)
from station.domain.product.products import load_products
from station.domain.sensors.sensor_spec import PUTTER_SENSOR, SensorSpec
from station.domain.signals.orientation import POSE_TOLERANCE_DEG, ZeroG, sense
from station.domain.signals.poses import POSES, Pose
from station.domain.signals.samples import SampleBlock
from station.domain.signals.stillness import StillnessThresholds, judge_window

AXIS_POSES = tuple(
    p for p in POSES.values() if np.count_nonzero(np.abs(p.gravity_body) > 1e-6) == 1
)


@st.composite
def sensors(draw: st.DrawFn) -> SensorSpec:
    """A sensor whose ±range fills a share of its ADC around mid-scale, with a noise and
    datasheet spreads of the kind accelerometers have (0.2…3 mg rms, ±0.25 g, ±5 %)."""
    bits = draw(st.integers(10, 16))
    range_g = draw(st.sampled_from([2.0, 4.0, 8.0, 16.0]))
    half = float(1 << (bits - 1))
    return SensorSpec(
        adc_bits=bits,
        zero_g_counts=half,
        counts_per_g=draw(st.floats(0.25, 1.0)) * half / range_g,
        range_g=range_g,
        gyro_dps_per_lsb=0.02,
        sample_rate_hz=500,
        zero_g_spread_g=draw(st.floats(0.0, 0.25)),
        sensitivity_tolerance=draw(st.floats(0.0, 0.05)),
        noise_g=draw(st.floats(2e-4, 3e-3)),
    )


def rescaled(sensor: SensorSpec, factor: float) -> SensorSpec:
    """``sensor`` with ``factor`` times its counts per g and range / factor (its ADC kept)."""
    return sensor.model_copy(
        update={"counts_per_g": sensor.counts_per_g * factor, "range_g": sensor.range_g / factor}
    )


def test_the_putters_thresholds_are_the_counts_they_always_were() -> None:
    limits = StillnessThresholds(sensor=PUTTER_SENSOR)
    assert limits == StillnessThresholds()
    assert (limits.accel_std_max_counts, limits.accel_drift_max_counts) == (4.0, 2.0)
    assert rail_margin_counts(PUTTER_SENSOR) == 16.0
    assert datasheet_reach_counts(PUTTER_SENSOR) == 1085
    assert load_products().get("DIXX-A12").sensor == PUTTER_SENSOR


def test_thresholds_given_in_counts_are_kept_whatever_the_sensor() -> None:
    d16 = load_products().get("DIXX-D16").sensor
    given_ = StillnessThresholds(sensor=d16, accel_std_max_counts=55.0)
    assert given_.accel_std_max_counts == 55.0
    assert given_.accel_drift_max_counts == pytest.approx(
        StillnessThresholds(sensor=d16).accel_drift_max_counts
    )


@given(sensors(), st.floats(0.25, 4.0))
def test_thresholds_scale_with_the_sensors_counts_per_g(sensor: SensorSpec, factor: float) -> None:
    other = rescaled(sensor, factor)
    one, two = StillnessThresholds(sensor=sensor), StillnessThresholds(sensor=other)
    assert two.accel_std_max_counts == pytest.approx(factor * one.accel_std_max_counts)
    assert two.accel_drift_max_counts == pytest.approx(factor * one.accel_drift_max_counts)
    assert two.gravity_tolerance_g == one.gravity_tolerance_g  # in g already
    assert rail_margin_counts(other) == pytest.approx(factor * rail_margin_counts(sensor))
    # The spread a still window may have never falls below four times the sensor's noise.
    assert one.accel_std_max_counts >= 4 * sensor.noise_g * sensor.counts_per_g * (1 - 1e-12)


def still_window(
    sensor: SensorSpec, gravity: np.ndarray, rng: np.random.Generator, n: int = 1024
) -> SampleBlock:
    """``n`` samples of a unit of ``sensor`` at rest with ``gravity`` (g) in body axes."""
    accel = sensor.zero_g_counts + sensor.counts_per_g * (
        gravity + rng.normal(0.0, sensor.noise_g, (n, 3))
    )
    gyro = rng.normal(0.0, 0.05, (n, 3))
    return SampleBlock.from_columns(np.arange(n, dtype=float), accel, gyro, np.zeros(n))


@settings(deadline=None, max_examples=50)
@given(sensors(), st.sampled_from(AXIS_POSES), st.integers(0, 2**32 - 1))
def test_any_sensors_still_window_is_still_and_its_tremor_and_rail_are_not(
    sensor: SensorSpec, pose: Pose, seed: int
) -> None:
    rng = np.random.default_rng(seed)
    limits = StillnessThresholds(sensor=sensor)
    window = still_window(sensor, pose.gravity_body, rng)
    assert judge_window(window, limits).still, judge_window(window, limits).reasons
    # A tremor whose spread is twice the limit (a sine's rms is its amplitude / √2).
    shaken = SampleBlock(window.rows.copy())
    amplitude = 2 * np.sqrt(2) * limits.accel_std_max_counts
    shaken.accel[:, 0] += amplitude * np.sin(np.arange(len(window)) * 0.3)
    verdict = judge_window(shaken, limits)
    assert verdict.motion
    assert any(reason.startswith("accel x spread") for reason in verdict.reasons)
    # One sample at the top of this sensor's ADC: the axis is at its rail.
    railed = SampleBlock(window.rows.copy())
    railed.accel[7, 1] = sensor.adc_max
    assert judge_window(railed, limits).saturated_axes == ("y",)


offsets_and_sensitivities = st.tuples(
    st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
    st.lists(st.floats(-1.0, 1.0), min_size=3, max_size=3),
)


@given(sensors(), st.sampled_from(AXIS_POSES), offsets_and_sensitivities)
def test_any_sensors_unit_within_its_datasheet_is_seen_in_the_pose_it_lies_in(
    sensor: SensorSpec, pose: Pose, shares: tuple[list[float], list[float]]
) -> None:
    offset = sensor.zero_g_counts + sensor.zero_g_spread_counts * np.array(shares[0])
    sensitivity = sensor.counts_per_g * (1 + sensor.sensitivity_tolerance * np.array(shares[1]))
    counts = offset + sensitivity * pose.gravity_body
    sensed = sense(counts, zero_g=ZeroG.datasheet(sensor))
    assert sensed.matches(pose, tolerance_deg=0.01)
    for other in AXIS_POSES:
        if other is not pose:
            assert not sensed.matches(other, POSE_TOLERANCE_DEG)


@given(sensors(), offsets_and_sensitivities)
def test_any_sensors_six_poses_screen_clean_ninety_degrees_apart(
    sensor: SensorSpec, shares: tuple[list[float], list[float]]
) -> None:
    offset = sensor.zero_g_counts + sensor.zero_g_spread_counts * np.array(shares[0])
    sensitivity = sensor.counts_per_g * (1 + sensor.sensitivity_tolerance * np.array(shares[1]))
    poses = np.array([offset + sensitivity * p.gravity_body for p in AXIS_POSES])
    result = screen(poses[None], GeometryLimits(sensor=sensor))
    assert Finding(int(result.finding[0])) is Finding.OK
    assert result.min_angle_deg[0] == pytest.approx(90.0, abs=6.0)
