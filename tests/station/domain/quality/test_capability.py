"""Capability math against direct formulas, for arbitrary data (hypothesis)."""

import itertools
import math
import statistics

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from station.domain.quality.capability import (
    D4,
    HISTOGRAM_BINS,
    MAX_DATA_BINS,
    cp,
    cpk,
    data_bins,
    histogram_bins,
    individuals_limits,
    marginal_zones,
    shifted_moments,
)

values = st.lists(
    st.floats(min_value=700.0, max_value=3000.0, allow_nan=False), min_size=2, max_size=200
)


@given(values, st.floats(min_value=-5000.0, max_value=5000.0))
def test_shifted_sums_give_the_mean_and_sample_deviation(xs: list[float], shift: float) -> None:
    deviations = [x - shift for x in xs]
    mean, std = shifted_moments(
        len(xs), math.fsum(deviations), math.fsum(d * d for d in deviations), shift
    )
    assert mean == pytest.approx(statistics.fmean(xs), rel=1e-12, abs=1e-9)
    assert std is not None
    assert std == pytest.approx(statistics.stdev(xs), rel=1e-6, abs=1e-6)


def test_one_value_has_no_deviation_and_none_has_no_mean() -> None:
    assert shifted_moments(1, 2.0, 4.0, 2048.0) == (2050.0, None)
    assert shifted_moments(0, 0.0, 0.0, 2048.0) == (None, None)


@given(
    st.floats(min_value=-100, max_value=100),
    st.floats(min_value=0.01, max_value=50),
    st.floats(min_value=-100, max_value=100),
    st.floats(min_value=0.1, max_value=100),
)
def test_cpk_never_exceeds_cp_and_equals_it_when_centred(
    mean: float, std: float, lower: float, width: float
) -> None:
    upper = lower + width
    assert cp(std, lower, upper) == pytest.approx(width / (6 * std))
    capability = cpk(mean, std, lower, upper)
    assert capability is not None
    assert capability <= width / (6 * std) + 1e-9
    assert cpk((lower + upper) / 2, std, lower, upper) == pytest.approx(width / (6 * std))


def test_one_sided_limits_give_cpk_only() -> None:
    assert cp(1.0, None, 30.0) is None
    assert cpk(6.0, 2.0, None, 30.0) == pytest.approx(4.0)
    assert cpk(6.0, 2.0, 0.0, None) == pytest.approx(1.0)
    assert cpk(6.0, 0.0, 0.0, 30.0) is None


@given(st.floats(min_value=-1000, max_value=1000), st.floats(min_value=0.1, max_value=1000))
def test_histogram_spans_the_limits_with_overhang(lower: float, width: float) -> None:
    upper = lower + width
    start, bin_width, bins = histogram_bins(lower, upper)
    assert bins == HISTOGRAM_BINS
    assert start == pytest.approx(lower - width / 4)
    assert start + bins * bin_width == pytest.approx(upper + width / 4)
    low_zone, high_zone = marginal_zones(lower, upper)
    assert (low_zone - lower, upper - high_zone) == (
        pytest.approx(0.1 * width),
        pytest.approx(0.1 * width),
    )


@given(st.floats(min_value=-1e4, max_value=1e4), st.floats(min_value=0, max_value=100))
def test_individuals_limits_are_three_short_term_sigmas(mean: float, mr_bar: float) -> None:
    assume(math.isfinite(mean))
    lcl, ucl, mr_ucl = individuals_limits(mean, mr_bar)
    assert ucl - mean == pytest.approx(mean - lcl)
    assert ucl - mean == pytest.approx(2.66 * mr_bar, rel=1e-3, abs=1e-12)
    assert mr_ucl == pytest.approx(D4 * mr_bar)


@st.composite
def near_equal(draw: st.DrawFn) -> list[float]:
    """Values a few doubles apart, as a solver gives for units alike (``32276.0`` and
    ``32276.000000000004``): the histogram's and the box plot's hardest data."""
    base = draw(st.floats(min_value=-1e6, max_value=1e6))
    steps = draw(st.lists(st.integers(0, 8), min_size=1, max_size=50))
    return [float(base + s * np.spacing(base)) for s in steps]


spread_out = st.lists(st.floats(min_value=-1e6, max_value=1e6), min_size=1, max_size=200)


@given(st.one_of(near_equal(), spread_out))
def test_data_bins_hold_every_value_in_increasing_bins(xs: list[float]) -> None:
    edges, counts, below, above = data_bins(xs)
    assert all(a < b for a, b in itertools.pairwise(edges))
    assert 1 <= len(counts) <= MAX_DATA_BINS
    assert len(edges) == len(counts) + 1
    assert sum(counts) + below + above == len(xs)
    assert below <= sum(1 for x in xs if x < np.percentile(xs, 25))
    assert above <= sum(1 for x in xs if x > np.percentile(xs, 75))
