"""Decision rules (ILAC-G8:09/2019, JCGM 106:2012): simple acceptance as before, guarded
acceptance with a guard band w = U, named by the profile and recorded by the verdict."""

from collections.abc import Callable
from importlib import resources

import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.domain.errors import InputError
from station.domain.product.judging import (
    Matrix,
    Measured,
    check_rules,
    limit_checks,
    rejudge,
    uncertainty_of,
)
from station.domain.product.limits import load_profile, parse_profiles

SHIPPED = load_profile()
GUARDED = SHIPPED.model_copy(update={"decision_rule": "guarded"})
LOW, HIGH = SHIPPED.offset_counts.lower, SHIPPED.offset_counts.upper
assert LOW is not None
assert HIGH is not None

offsets = st.floats(LOW - 50, HIGH + 50)
spreads = st.floats(0.0, 40.0)


@given(value=offsets, u=spreads)
def test_simple_acceptance_ignores_the_uncertainty(value: float, u: float) -> None:
    with_u = Measured(offset=(value, 2048.0, 2048.0), uncertainty={"offset": (u, u, u)})
    without = Measured(offset=(value, 2048.0, 2048.0))
    assert limit_checks(SHIPPED, with_u) == limit_checks(SHIPPED, without)


@given(value=offsets, u=spreads)
def test_guarded_acceptance_takes_the_value_plus_and_minus_u(value: float, u: float) -> None:
    measured = Measured(offset=(value, 2048.0, 2048.0), uncertainty={"offset": (u, 0.0, 0.0)})
    guarded = limit_checks(GUARDED, measured)
    simple = limit_checks(SHIPPED, measured)
    inside = LOW + u <= value <= HIGH - u
    assert (guarded == []) is inside
    # Guarded acceptance accepts nothing simple acceptance refuses.
    if simple:
        assert guarded
    if guarded and not simple:
        assert guarded[0].code == "offset"
        assert "guarded acceptance" in guarded[0].message
        assert guarded[0].axis == "x"
        assert (guarded[0].lower, guarded[0].upper) == (LOW, HIGH)


@given(value=offsets)
def test_a_guard_band_of_zero_is_simple_acceptance(value: float) -> None:
    measured = Measured(offset=(value, 2048.0, 2048.0), uncertainty={"offset": (0.0, 0.0, 0.0)})
    assert limit_checks(GUARDED, measured) == limit_checks(SHIPPED, measured)


def test_without_an_uncertainty_the_guarded_rule_judges_the_value() -> None:
    edge = Measured(offset=(HIGH - 0.1, 2048.0, 2048.0))
    assert limit_checks(GUARDED, edge) == []


def test_the_gyro_bias_is_guarded_too_and_the_what_if_compares_rules() -> None:
    bias_high = SHIPPED.gyro_bias_dps.upper
    assert bias_high is not None
    measured = Measured(
        offset=(2048.0, 2048.0, 2048.0),
        gyro_bias=(bias_high - 0.01, 0.0, 0.0),
        uncertainty=uncertainty_of((0.1, 0.1, 0.1), None, (0.05, 0.05, 0.05)),
    )
    assert rejudge([], SHIPPED, measured) == []
    [reason] = rejudge([], GUARDED, measured)
    assert (reason.code, reason.axis) == ("gyro_bias", "x")


def test_the_rule_is_part_of_the_profile_and_absent_leaves_its_hash_alone() -> None:
    assert SHIPPED.decision_rule is None
    assert SHIPPED.rule == "simple"
    assert "decision_rule" not in SHIPPED.document
    assert GUARDED.rule == "guarded"
    assert GUARDED.document["decision_rule"] == "guarded"
    assert GUARDED.sha256 != SHIPPED.sha256


def test_a_limits_file_names_the_rule_and_a_rule_unknown_is_refused() -> None:
    text = (resources.files("station.domain.profiles") / "limits.toml").read_text()
    named = text.replace('version = "1"\n', 'version = "1"\ndecision_rule = "guarded"\n', 1)
    assert parse_profiles(named, "limits.toml")["kxm52-production"].rule == "guarded"
    wrong = named.replace('decision_rule = "guarded"', 'decision_rule = "strict"')
    with pytest.raises(InputError, match="decision_rule"):
        parse_profiles(wrong, "limits.toml")


WHOLE = load_profile(None, "whole-unit")
WHOLE_GUARDED = WHOLE.model_copy(update={"decision_rule": "guarded"})
assert WHOLE.gyro_misalignment is not None
assert WHOLE.gyro_scale_error is not None
K_LOW, K_HIGH = WHOLE.gyro_misalignment.lower, WHOLE.gyro_misalignment.upper
ERROR_HIGH = WHOLE.verification_error_mg.upper
assert K_LOW is not None
assert K_HIGH is not None
assert ERROR_HIGH is not None


def _matrix(entry: Callable[[int, int], float]) -> Matrix:
    """The 3×3 matrix of ``entry(i, j)``."""
    rows = [(entry(i, 0), entry(i, 1), entry(i, 2)) for i in range(3)]
    return (rows[0], rows[1], rows[2])


def _k_with(value: float, at: tuple[int, int]) -> Matrix:
    """K = I with one entry set to ``value``."""
    return _matrix(lambda i, j: value if (i, j) == at else 1.0 if i == j else 0.0)


@given(
    value=st.floats(K_LOW - 0.02, K_HIGH + 0.02),
    u=st.floats(0.0, 0.03),
    at=st.sampled_from([(i, j) for i in range(3) for j in range(3) if i != j]),
)
def test_an_entry_of_k_is_judged_with_its_u_under_the_guarded_rule(
    value: float, u: float, at: tuple[int, int]
) -> None:
    k = _k_with(value, at)
    spread = _matrix(lambda i, j: u if (i, j) == at else 0.0)
    measured = Measured(
        gyro_matrix=k, uncertainty=uncertainty_of(None, None, None, gyro_matrix=spread)
    )
    simple = limit_checks(WHOLE, measured)
    guarded = limit_checks(WHOLE_GUARDED, measured)
    assert (simple == []) is (K_LOW <= value <= K_HIGH)
    assert (guarded == []) is (K_LOW + u <= value <= K_HIGH - u)
    if guarded and not simple:  # inside the bounds by less than U: the guard refused it
        [reason] = guarded
        assert (reason.code, reason.axis) == ("gyro_misalignment", "xyz"[at[0]])
        assert reason.uncertainty == u
        assert "guarded acceptance" in reason.message


@given(value=st.floats(-0.04, 0.04), u=st.floats(0.0, 0.03), axis=st.integers(0, 2))
def test_a_scale_error_of_k_is_judged_with_its_u_under_the_guarded_rule(
    value: float, u: float, axis: int
) -> None:
    bounds = WHOLE.gyro_scale_error
    assert bounds is not None
    k = _k_with(1.0 + value, (axis, axis))
    spread = _matrix(lambda i, j: u if i == j == axis else 0.0)
    measured = Measured(
        gyro_matrix=k, uncertainty=uncertainty_of(None, None, None, gyro_matrix=spread)
    )
    scale = k[axis][axis] - 1.0
    assert (limit_checks(WHOLE, measured) == []) is bounds.contains(scale)
    assert (limit_checks(WHOLE_GUARDED, measured) == []) is bounds.guarded(scale, u)


@given(error=st.floats(0.0, ERROR_HIGH + 3.0), u=st.floats(0.0, 6.0))
def test_the_verification_error_is_judged_with_its_u_under_the_guarded_rule(
    error: float, u: float
) -> None:
    measured = Measured(verification=(12, error), uncertainty=uncertainty_of(None, None, None, u))
    simple = limit_checks(WHOLE, measured)
    guarded = limit_checks(WHOLE_GUARDED, measured)
    assert (simple == []) is (error <= ERROR_HIGH)
    assert (guarded == []) is (error <= ERROR_HIGH - u)  # the acceptance limit: TU - w
    if guarded and not simple:
        [reason] = guarded
        assert (reason.code, reason.pose, reason.uncertainty) == ("verification_error", 12, u)
        assert f"U = {u:.3g} mg" in reason.message


def test_the_rules_name_the_guarded_rule_where_a_value_carries_its_u() -> None:
    measured = Measured(
        offset=(2048.0, 2048.0, 2048.0),
        uncertainty=uncertainty_of((0.1, 0.1, 0.1), None, None, 0.5),
    )
    rules = check_rules(WHOLE_GUARDED, measured)
    assert rules["offset"] == rules["verification_error"] == "guarded"
    # No U known: judged by the value alone, and the record says so.
    assert rules["sensitivity"] == rules["gyro_scale"] == rules["pose_noise"] == "simple"
    assert set(check_rules(WHOLE, measured).values()) == {"simple"}
