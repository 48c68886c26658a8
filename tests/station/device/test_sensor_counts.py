"""The driver and the virtual putter of a product whose sensor is not the putter's
12-bit one: its counts pass the link whole (station.domain.sensors.sensor_spec)."""

import numpy as np

from station.device import DeviceCalibration, PutterDriver
from station.domain.product.products import load_products
from station.domain.signals.poses import pose
from station.simulator import VirtualPutter


def test_a_16_bit_unit_streams_its_counts_to_a_driver_opened_for_its_adc() -> None:
    d16 = load_products().get("DIXX-D16").sensor
    with VirtualPutter(seed=11, serial="PT000042", speed=20.0, sensor=d16) as putter:
        url = putter.serve_pty()
        with PutterDriver.open(url, reply_timeout=0.3, adc_max=d16.adc_max) as driver:
            # A fresh unit holds its own sensor's nominal coefficients.
            assert driver.read_calibration() == DeviceCalibration.factory_default(d16)
            driver.start_stream()
            rows = driver.wait_samples(1000, timeout=5.0)
        truth = putter.truth
    # Its counts lie beyond the 12-bit ADC's 4095, and none was dropped as corrupt.
    assert rows.accel.min() > 4095
    at_rest = truth.offset_counts + truth.sensitivity_counts_per_g * (
        truth.cross_axis @ pose("face_up").gravity_body
    )
    np.testing.assert_allclose(rows.accel.mean(axis=0), at_rest, atol=3e-3 * d16.counts_per_g)
