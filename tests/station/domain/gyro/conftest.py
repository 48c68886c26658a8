"""Shared fixtures: simulated logs of the centrifuge test with a known truth."""

import pytest

from station.domain.gyro.log import GyroLog
from station.domain.gyro.model import GyroErrorModel
from station.domain.gyro.simulate import Noise, paper_truth, simulate_log

NOISE = Noise(gyro_dps=0.01, acc_g=0.001)


@pytest.fixture(scope="session")
def paper_model() -> GyroErrorModel:
    """The paper's truth: scale-factor form only, 581 / 612 / −613 ppm/g."""
    return paper_truth()


@pytest.fixture(scope="session")
def paper_log(paper_model: GyroErrorModel) -> GyroLog:
    """The default test plan simulated from the paper's truth."""
    log, _ = simulate_log(paper_model, noise=NOISE, seed=7)
    return log
