"""Western Electric rules against their definitions, for arbitrary charts (hypothesis)."""

from hypothesis import given
from hypothesis import strategies as st

from station.domain.quality.control import RULES, western_electric

#: Values as multiples of a quarter σ about a centre of 0 with σ = 1: exact arithmetic,
#: and points on the zone edges and the centre line occur often.
zs = st.lists(st.integers(-16, 16).map(lambda q: q / 4), max_size=40)


def _completes(z: list[float], end: int, rule: int) -> bool:
    """Whether point ``end`` completes rule ``rule``, read straight from the rule's text."""
    _, window, needed, beyond = next(r for r in RULES if r[0] == rule)
    if end < window - 1:
        return False
    span = z[end - window + 1 : end + 1]
    return any(
        side * z[end] > beyond and sum(side * x > beyond for x in span) >= needed
        for side in (1, -1)
    )


@given(zs)
def test_each_point_is_flagged_with_exactly_the_rules_it_completes(z: list[float]) -> None:
    flags = western_electric(z, 0.0, 1.0)
    assert flags == [[r for r in (1, 2, 3, 4) if _completes(z, i, r)] for i in range(len(z))]


@given(zs, st.floats(-1e4, 1e4), st.sampled_from([0.01, 0.5, 3.0, 250.0]))
def test_the_flags_do_not_depend_on_the_charts_scale_or_position(
    z: list[float], centre: float, sigma: float
) -> None:
    # Scaled back, a value may sit a rounding error off a zone edge: keep clear of edges.
    shifted = [x + 1 / 8 if x >= 0 else x - 1 / 8 for x in z]
    values = [centre + sigma * x for x in shifted]
    assert western_electric(values, centre, sigma) == western_electric(shifted, 0.0, 1.0)


@given(zs)
def test_a_chart_mirrored_about_its_centre_signals_at_the_same_points(z: list[float]) -> None:
    assert western_electric([-x for x in z], 0.0, 1.0) == western_electric(z, 0.0, 1.0)


@given(st.integers(1, 30), st.booleans())
def test_a_run_of_points_on_one_side_signals_from_its_eighth(n: int, above: bool) -> None:
    value = 0.5 if above else -0.5
    flags = western_electric([value] * n, 0.0, 1.0)
    assert [4 in f for f in flags] == [i >= 7 for i in range(n)]
    assert all(f in ([], [4]) for f in flags)


def test_a_point_beyond_three_sigma_signals_rule_1_and_no_spread_signals_nothing() -> None:
    assert western_electric([0.0, 3.5, 0.0, -3.01], 0.0, 1.0) == [[], [1], [], [1]]
    assert western_electric([1.0, 5.0], 1.0, 0.0) == [[], []]
