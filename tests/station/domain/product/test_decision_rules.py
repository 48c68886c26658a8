"""Decision rules (ILAC-G8:09/2019, JCGM 106:2012): simple acceptance as before, guarded
acceptance with a guard band w = U, named by the profile and recorded by the verdict."""

from importlib import resources

import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.domain.errors import InputError
from station.domain.product.judging import Measured, limit_checks, rejudge, uncertainty_of
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
