"""A DIXX-D16 unit's run end to end over a real pty: its 16-bit counts are judged, fitted
and recorded as its own sensor's (station.domain.sensors.sensor_spec)."""

from pathlib import Path

import numpy as np
import pytest

from station.domain.product.products import load_products
from station.domain.product.run_settings import RunSettings
from station.domain.signals.stillness import StillnessThresholds
from tests.station.run.test_unit_run import Bench, done

D16 = load_products().get("DIXX-D16")


@pytest.mark.parametrize("seed", [11, 12])
def test_a_dixx_d16_unit_is_calibrated_in_its_own_counts(tmp_path: Path, seed: int) -> None:
    settings = RunSettings(stillness=StillnessThresholds(sensor=D16.sensor))
    bench = Bench(tmp_path, seed=seed, settings=settings, product=D16)
    try:
        bench.drive(done, timeout=120.0)
    finally:
        bench.close()
    record = bench.run.record
    assert record is not None
    assert record.verdict == "pass", record.failures
    assert (record.part_number, record.limits.name) == ("DIXX-D16", D16.limits_profile)
    truth = bench.putter.truth
    # The poses are the 16-bit sensor's counts: about 1 g (8192 counts) from its zero g.
    means = np.array([p.mean.as_tuple() for p in record.fit_poses()])
    assert np.abs(means - D16.sensor.zero_g_counts).max() > 0.9 * D16.sensor.counts_per_g
    assert record.coefficients is not None
    assert record.uncertainty is not None
    u = record.uncertainty
    assert u.offset is not None
    assert u.sensitivity is not None
    offset = np.array(record.coefficients.offset.as_tuple())
    sensitivity = np.array(record.coefficients.sensitivity.as_tuple())
    # The fit lands on the simulator's truth within the run's own uncertainty budget, in
    # the sensor's counts: the recorded U (k = 2, JCGM 100:2008) taken to k = 3, so that
    # a coefficient outside it is a fault, not the 5 % a k = 2 interval leaves out.
    k3 = 3 / 2
    assert np.all(np.abs(offset - truth.offset_counts) <= k3 * np.array(u.offset.as_tuple()))
    assert np.all(
        np.abs(sensitivity - truth.sensitivity_counts_per_g)
        <= k3 * np.array(u.sensitivity.as_tuple())
    )
    # A budget as tight in g as the 12-bit putter's (its zero g to 0.2 counts, 0.24 mg).
    assert np.all(np.array(u.offset.as_tuple()) / D16.sensor.counts_per_g < 0.2 / 819.2)
