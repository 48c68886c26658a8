"""The virtual putter's sensor model against the brief's physics."""

import dataclasses

import numpy as np
import pytest

from station.domain.sensors.sensor import ADC_MAX
from station.simulator import SensorTruth, Thermal
from station.simulator.sensor import GYRO_SENSE_AXIS, accelerometer_counts, gyro_rates


@pytest.fixture
def truth() -> SensorTruth:
    return SensorTruth.draw(np.random.default_rng(17))


def test_drawn_units_stay_within_the_datasheet_spread() -> None:
    for seed in range(200):
        t = SensorTruth.draw(np.random.default_rng(seed))
        assert np.all(np.abs(t.offset_counts - 2048) <= 207)
        assert np.all(np.abs(t.sensitivity_counts_per_g / 819.2 - 1) <= 0.05)
        np.testing.assert_array_equal(np.diag(t.cross_axis), 1.0)
        assert np.abs(t.cross_axis - np.eye(3)).max() <= 0.02
        assert np.all(np.abs(np.abs(t.gyro_g_sensitivity_per_g) - 600e-6) <= 30e-6)


def test_the_true_matrix_maps_counts_back_to_g(truth: SensorTruth) -> None:
    force = np.array([[0.3, -0.5, 0.81]])
    quiet = dataclasses.replace(truth, noise_counts=0.0)
    counts = accelerometer_counts(
        quiet, np.repeat(force, 1, 0), np.array([25.0]), np.random.default_rng(0)
    )
    # Rounding to whole counts is the only error left: half a count is 0.6 mg.
    np.testing.assert_allclose(
        truth.matrix @ (counts[0] - truth.offset_counts), force[0], atol=1e-3
    )


def test_counts_are_whole_noisy_and_centred_on_the_model(truth: SensorTruth) -> None:
    n = 20_000
    force = np.tile([0.0, 0.0, 1.0], (n, 1))
    counts = accelerometer_counts(truth, force, np.full(n, 25.0), np.random.default_rng(1))
    np.testing.assert_array_equal(counts, np.rint(counts))
    expected = truth.offset_counts + truth.sensitivity_counts_per_g * truth.cross_axis[:, 2]
    np.testing.assert_allclose(counts.mean(axis=0), expected, atol=0.05)
    # White noise of 1 count plus quantisation (1/12 count²).
    np.testing.assert_allclose(counts.std(axis=0), np.sqrt(1 + 1 / 12), rtol=0.05)


def test_the_adc_clips_at_0_and_4095(truth: SensorTruth) -> None:
    force = np.array([[4.0, -4.0, 0.0]])
    counts = accelerometer_counts(truth, force, np.array([25.0]), np.random.default_rng(2))
    assert counts[0, 0] == ADC_MAX
    assert counts[0, 1] == 0


def test_offset_and_sensitivity_drift_with_temperature(truth: SensorTruth) -> None:
    quiet = dataclasses.replace(truth, noise_counts=0.0)
    force = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]])
    rng = np.random.default_rng(3)
    cold = accelerometer_counts(quiet, force, np.full(2, 25.0), rng)
    hot = accelerometer_counts(quiet, force, np.full(2, 65.0), rng)
    np.testing.assert_allclose(hot[0] - cold[0], 40 * truth.offset_tempco_counts_per_c, atol=1.0)
    span_ratio = (hot[1] - hot[0]) / (cold[1] - cold[0])
    # Rounding to whole counts over a ~820-count span: 1.5e-3 relative at most.
    np.testing.assert_allclose(span_ratio, 1 + 40 * truth.sensitivity_tempco_per_c, atol=2e-3)


def test_gyros_at_rest_read_their_bias_whatever_the_gravity(truth: SensorTruth) -> None:
    n = 20_000
    rng = np.random.default_rng(4)
    for force in np.eye(3):
        rates = gyro_rates(truth, np.zeros((n, 3)), np.tile(force, (n, 1)), rng)
        # Paper 2: acceleration alone gives no error (no deg/s/g bias).
        np.testing.assert_allclose(rates.mean(axis=0), truth.gyro_bias_dps, atol=0.003)


@pytest.mark.parametrize("gyro", [0, 1, 2])
def test_g_sensitivity_is_a_scale_factor_error_on_the_sense_axis_only(
    truth: SensorTruth, gyro: int
) -> None:
    quiet = dataclasses.replace(truth, gyro_noise_dps=0.0)
    rng = np.random.default_rng(5)
    rate = np.zeros((1, 3))
    rate[0, gyro] = 575.0  # the paper's centrifuge rate
    sense = np.zeros((1, 3))
    sense[0, GYRO_SENSE_AXIS[gyro]] = 30.0  # and its 30 g
    other = np.zeros((1, 3))
    other[0, gyro] = 30.0  # along the input axis: not the sense axis
    plain = gyro_rates(quiet, rate, np.zeros((1, 3)), rng)[0, gyro]
    sensed = gyro_rates(quiet, rate, sense, rng)[0, gyro]
    along_input = gyro_rates(quiet, rate, other, rng)[0, gyro]
    error_ppm = (sensed - plain) / 575.0 / 30.0 * 1e6
    assert error_ppm == pytest.approx(truth.gyro_g_sensitivity_per_g[gyro] * 1e6)
    assert 570 < abs(error_ppm) < 630
    assert along_input == pytest.approx(plain)


def test_the_board_warms_up_towards_ambient_plus_self_heating() -> None:
    thermal = Thermal(ambient_c=22.0, self_heating_c=3.0, time_constant_s=100.0)
    t = np.array([0.0, 100.0, 1000.0])
    np.testing.assert_allclose(
        thermal.at(t), [22.0, 22.0 + 3.0 * (1 - np.exp(-1)), 25.0], atol=1e-3
    )
