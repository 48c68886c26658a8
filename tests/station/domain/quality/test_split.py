"""A split's group figures (Tukey's box plot, Cpk) for arbitrary data (hypothesis)."""

import statistics

from hypothesis import given
from hypothesis import strategies as st

from station.domain.quality.split import FENCE, group_stats
from tests.station.domain.quality.test_capability import near_equal, spread_out


@given(st.one_of(near_equal(), spread_out))
def test_whiskers_are_the_extreme_values_within_the_fences(xs: list[float]) -> None:
    group = group_stats("g", xs, None, None)
    iqr = group.q3 - group.q1
    low_fence, high_fence = group.q1 - FENCE * iqr, group.q3 + FENCE * iqr
    assert group.n == len(xs)
    assert (group.minimum, group.maximum) == (min(xs), max(xs))
    assert group.minimum <= group.q1 <= group.median <= group.q3 <= group.maximum
    assert group.whisker_low == min(x for x in xs if x >= low_fence)
    assert group.whisker_high == max(x for x in xs if x <= high_fence)
    beyond = sum(1 for x in xs if x < low_fence) + sum(1 for x in xs if x > high_fence)
    assert group.outliers == beyond
    assert group.mean == statistics.fmean(xs) or abs(group.mean - statistics.fmean(xs)) <= (
        1e-12 * max(abs(x) for x in xs)
    )


@given(
    st.lists(st.floats(min_value=0.0, max_value=10.0), min_size=1, max_size=50),
    st.floats(min_value=0.0, max_value=10.0),
    st.floats(min_value=0.0, max_value=10.0),
)
def test_out_of_limits_counts_the_values_strictly_outside(
    xs: list[float], a: float, b: float
) -> None:
    lower, upper = min(a, b), max(a, b)
    group = group_stats("g", xs, lower, upper)
    assert group.out_of_limits == sum(1 for x in xs if x < lower or x > upper)
