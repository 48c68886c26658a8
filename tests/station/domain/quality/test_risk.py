"""Global false-accept and false-reject risks (JCGM 106): against a brute-force Monte
Carlo, and the laws a decision rule must obey."""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.domain.quality.risk import decision_risks, normality

means = st.floats(-2.0, 2.0)
process = st.floats(0.2, 2.0)
uncertainties = st.floats(0.01, 1.0)


@given(mean=means, sigma_p=process, u=uncertainties)
def test_guarding_trades_false_accepts_for_false_rejects(
    mean: float, sigma_p: float, u: float
) -> None:
    observed = float(np.hypot(sigma_p, u))
    simple = decision_risks(mean, observed, u, -3.0, 3.0)
    guarded = decision_risks(mean, observed, u, -3.0, 3.0, guard=2 * u)
    assert 0.0 <= simple.false_accept <= 1.0
    assert 0.0 <= simple.false_reject <= 1.0
    assert guarded.false_accept <= simple.false_accept + 1e-12
    assert guarded.false_reject >= simple.false_reject - 1e-12


@given(mean=means, sigma_p=process)
def test_a_perfect_measurement_makes_no_wrong_decision(mean: float, sigma_p: float) -> None:
    risks = decision_risks(mean, sigma_p, 0.0, -3.0, 3.0)
    assert risks.false_accept == pytest.approx(0.0, abs=1e-12)
    assert risks.false_reject == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(("guard", "lower"), [(0.0, -1.0), (0.3, -1.0), (0.0, None)])
def test_the_risks_are_those_of_simulated_units(guard: float, lower: float | None) -> None:
    rng = np.random.default_rng(106)
    mean, sigma_p, u, upper = 0.2, 0.6, 0.25, 1.0
    truth = rng.normal(mean, sigma_p, 2_000_000)
    measured = truth + rng.normal(0.0, u, truth.size)
    low = -np.inf if lower is None else lower
    inside = (truth >= low) & (truth <= upper)
    accepted = (measured >= low + guard) & (measured <= upper - guard)
    risks = decision_risks(mean, float(np.hypot(sigma_p, u)), u, lower, upper, guard)
    # 2e6 units: a rate near 3 % is known to ±0.02 % (1σ).
    assert risks.false_accept == pytest.approx(np.mean(accepted & ~inside), abs=1e-3)
    assert risks.false_reject == pytest.approx(np.mean(~accepted & inside), abs=1e-3)


def test_the_normality_check_tells_the_simulators_uniform_population_from_a_normal_one() -> None:
    # The risks assume a normal population; on a uniform one of the same spread (no
    # tails) the check says so, and on a normal one it does not.
    rng = np.random.default_rng(43)
    normal = normality(rng.normal(819.2, 10.0, 1000))
    uniform = normality(rng.uniform(800.0, 840.0, 1000))
    assert normal is not None
    assert uniform is not None
    assert normal.normal
    assert normal.values == 1000
    assert not uniform.normal
    assert uniform.statistic > normal.statistic


def test_too_few_or_equal_values_are_not_judged() -> None:
    assert normality([1.0, 2.0, 3.0]) is None
    assert normality([5.0] * 20) is None
