"""Limits profiles: reading, hashing, checking."""

import math
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.domain.errors import InputError
from station.domain.product.limits import (
    CHECKS,
    Bounds,
    check,
    load_profile,
    load_profiles,
    parse_profiles,
    profile_of,
)
from station.domain.record.records import LimitsRef, document_sha256
from station.domain.sensors.record_bounds import (
    ADC_SPAN,
    ERROR_MAX_MG,
    GYRO_RANGE_DPS,
    OFFSET_MAX_COUNTS,
    OFFSET_MIN_COUNTS,
    SENSITIVITY_MAX_COUNTS_PER_G,
)
from station.domain.sensors.sensor import (
    NOMINAL_OFFSET_COUNTS,
    NOMINAL_SENSITIVITY_COUNTS_PER_G,
    OFFSET_SPREAD_COUNTS,
)

PROFILE = """
[profiles.line-a]
version = "7"
offset_counts = { lower = 1841.0, upper = 2255.0 }
sensitivity_counts_per_g = { lower = 778.24, upper = 860.16 }
verification_error_mg = { upper = 30.0 }
pose_noise_counts = { upper = 8.0 }
gyro_bias_dps = { lower = -10.0, upper = 10.0 }
link_loss = { upper = 0.01 }
writeback_relative_error = { upper = 1e-6 }
"""


def test_shipped_profile_holds_the_datasheet_bounds() -> None:
    profile = load_profile()
    assert profile.name == "kxm52-production"
    assert profile.offset_counts.lower == NOMINAL_OFFSET_COUNTS - OFFSET_SPREAD_COUNTS
    assert profile.offset_counts.upper == NOMINAL_OFFSET_COUNTS + OFFSET_SPREAD_COUNTS
    assert profile.sensitivity_counts_per_g.lower == pytest.approx(
        NOMINAL_SENSITIVITY_COUNTS_PER_G * 0.95
    )
    assert profile.sensitivity_counts_per_g.upper == pytest.approx(
        NOMINAL_SENSITIVITY_COUNTS_PER_G * 1.05
    )


def test_hash_ignores_layout_but_not_bounds(tmp_path: Path) -> None:
    a = tmp_path / "a.toml"
    a.write_text(PROFILE)
    b = tmp_path / "b.toml"
    b.write_text("# comment\n" + PROFILE.replace(" = ", "="))
    c = tmp_path / "c.toml"
    c.write_text(PROFILE.replace("upper = 30.0", "upper = 31.0"))
    ha, hb, hc = (load_profile(p).sha256 for p in (a, b, c))
    assert ha == hb
    assert ha != hc
    assert load_profile(a).ref.version == "7"


def test_check_returns_a_typed_reason_with_the_bounds() -> None:
    profile = load_profile()
    assert check(profile, "offset", 2048.0, axis="x") is None
    reason = check(profile, "sensitivity", 870.5, axis="z")
    assert reason is not None
    assert (reason.code, reason.measured, reason.lower, reason.upper, reason.axis) == (
        "sensitivity",
        870.5,
        778.24,
        860.16,
        "z",
    )
    assert reason.message == "sensitivity z 870.5 counts/g outside [778.24, 860.16]"
    noisy = check(profile, "pose_noise", 9.5, axis="y", pose=2)
    assert noisy is not None
    assert noisy.pose == 2
    assert "(pose 3)" in noisy.message


def test_nan_always_fails() -> None:
    reason = check(load_profile(), "verification_error", math.nan)
    assert reason is not None
    assert reason.measured is None


@pytest.mark.parametrize("rule", ["simple", "guarded"])
@pytest.mark.parametrize(
    "code", sorted(code for code, field in CHECKS.items() if getattr(load_profile(), field))
)
@pytest.mark.parametrize("value", [math.inf, -math.inf])
def test_an_infinite_value_always_fails_even_against_a_one_sided_limit(
    rule: str, code: str, value: float
) -> None:
    profile = load_profile().model_copy(update={"rule": rule})
    assert check(profile, code, value, uncertainty=1.0) is not None


@given(low=st.floats(-1e6, 1e6), width=st.floats(0, 1e6), value=st.floats(-3e6, 3e6))
def test_bounds_contain_exactly_the_closed_interval(low: float, width: float, value: float) -> None:
    bounds = Bounds(lower=low, upper=low + width)
    assert bounds.contains(value) == (low <= value <= low + width)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("not toml [", "not valid TOML"),
        ("[other]\nx = 1\n", "no [profiles.NAME] tables"),
        (PROFILE.replace('version = "7"\n', ""), "profile line-a: version: Field required"),
        (PROFILE.replace("upper = 30.0", "upper = -1.0, lower = 2.0"), "verification_error_mg"),
        (PROFILE + "bogus = 1\n", "profile line-a: bogus"),
        (PROFILE + "x = " + "[" * 900 + "]" * 900, "nested too deeply"),
        ("[profiles]\nx = 1\n", "profiles.x is not a table"),
        (PROFILE + "x = " + "9" * 4301, r"Exceeds the limit \(4300 digits\)"),
    ],
)
def test_bad_profile_files_name_the_problem(tmp_path: Path, content: str, message: str) -> None:
    path = tmp_path / "limits.toml"
    path.write_text(content)
    with pytest.raises(InputError, match=message.replace("[", r"\[")) as info:
        load_profiles(path)
    assert str(path) in str(info.value)


def test_unknown_profile_lists_the_known_ones(tmp_path: Path) -> None:
    path = tmp_path / "limits.toml"
    path.write_text(PROFILE)
    with pytest.raises(InputError, match=r"'line-b' not found \(known: line-a\)"):
        load_profile(path, "line-b")
    with pytest.raises(InputError, match="cannot read"):
        load_profiles(tmp_path / "missing.toml")


def test_a_fit_residual_limit_is_optional_and_hashes_only_when_set(tmp_path: Path) -> None:
    plain = tmp_path / "plain.toml"
    plain.write_text(PROFILE)
    limited = tmp_path / "limited.toml"
    limited.write_text(PROFILE + "fit_residual_counts = { upper = 5.0 }\n")
    without, with_limit = load_profile(plain), load_profile(limited)
    assert without.max_residual_counts is None
    assert "fit_residual_counts" not in without.document  # hashes as before the setting
    assert with_limit.max_residual_counts == 5.0
    assert with_limit.sha256 != without.sha256
    assert load_profile().max_residual_counts is None  # the shipped profile: the default


def test_the_six_pose_profile_hashes_as_before_the_gyro_bounds_existed() -> None:
    # The SHA-256 the runs before the gyro bounds carry (migration 0007 stores it).
    shipped = "e905f35844e7fbe48d498e538a70a61ff222e6cc049d0f477fc8f0d958c66800"
    profile = load_profile()
    assert profile.sha256 == shipped
    assert profile.gyro_scale_error is None
    assert not {"gyro_scale_error", "gyro_misalignment", "gyro_verification_deg"} & set(
        profile.document
    )
    # Absent bounds are not checked, whatever the value.
    assert check(profile, "gyro_scale", 0.5, axis="x") is None
    assert check(profile, "gyro_verification", 90.0) is None


def test_the_whole_unit_profile_bounds_the_gyro_matrix() -> None:
    profile = load_profile(None, "whole-unit")
    assert profile.gyro_scale_error is not None
    assert profile.gyro_misalignment is not None
    assert profile.sha256 != load_profile().sha256
    assert check(profile, "gyro_scale", 0.012, axis="y") is None
    reason = check(profile, "gyro_scale", -0.03, axis="y")
    assert reason is not None
    assert (reason.code, reason.axis, reason.lower) == ("gyro_scale", "y", -0.02)
    verification = check(profile, "gyro_verification", 0.6)
    assert verification is not None
    assert verification.message == "gyro verification 0.6 deg outside ≤ 0.25"
    assert profile.verification_error_mg.upper is not None
    assert profile.verification_error_mg.upper <= 5


#: Each bounded setting of a profile and the values its quantity can take.
PLAUSIBLE = {
    "offset_counts": (OFFSET_MIN_COUNTS, OFFSET_MAX_COUNTS),
    "sensitivity_counts_per_g": (0.0, SENSITIVITY_MAX_COUNTS_PER_G),
    "verification_error_mg": (0.0, ERROR_MAX_MG),
    "pose_noise_counts": (0.0, ADC_SPAN),
    "gyro_bias_dps": (-GYRO_RANGE_DPS, GYRO_RANGE_DPS),
    "link_loss": (0.0, 1.0),
    "writeback_relative_error": (0.0, 1.0),
    "gyro_scale_error": (-3.0, 1.0),
    "gyro_misalignment": (-2.0, 2.0),
    "gyro_verification_deg": (0.0, 180.0),
    "fit_residual_counts": (0.0, ADC_SPAN),
}


def _carried(field: str, bounds: dict[str, float | None]) -> LimitsRef:
    """The shipped profile with ``field`` set to ``bounds``, as a run carries it."""
    document = {**load_profile().document, field: bounds}
    return LimitsRef(
        name="kxm52-production",
        version="1",
        sha256=document_sha256(document),
        profile=document,
    )


@st.composite
def _outside(draw: st.DrawFn) -> tuple[str, float]:
    field = draw(st.sampled_from(sorted(PLAUSIBLE)))
    low, high = PLAUSIBLE[field]
    finite = {"allow_nan": False, "allow_infinity": False}
    value = draw(
        st.floats(min_value=high, exclude_min=True, **finite)
        | st.floats(max_value=low, exclude_max=True, **finite)
    )
    return field, value


@given(case=_outside(), side=st.sampled_from(["lower", "upper"]))
def test_a_bound_outside_what_its_quantity_can_take_is_refused_from_a_run_and_a_file(
    case: tuple[str, float], side: str
) -> None:
    field, value = case
    bounds = {"lower": None, "upper": None, side: value}
    with pytest.raises(InputError, match=f"limits.profile: {field}: .*{side} ") as carried:
        profile_of(_carried(field, bounds))
    assert "outside" in str(carried.value)
    lines = [line for line in PROFILE.splitlines() if not line.startswith(f"{field} = ")]
    text = "\n".join([*lines, f"{field} = {{ {side} = {value!r} }}"])
    with pytest.raises(InputError, match=f"profile line-a: {field}: .*{side} "):
        parse_profiles(text, "limits.toml")


@given(field=st.sampled_from(sorted(PLAUSIBLE)), data=st.data())
def test_bounds_within_what_their_quantity_can_take_are_kept(
    field: str, data: st.DataObject
) -> None:
    low, high = PLAUSIBLE[field]
    lower = data.draw(st.floats(low, high))
    upper = data.draw(st.floats(lower, high))
    profile = profile_of(_carried(field, {"lower": lower, "upper": upper}))
    assert profile is not None
    assert getattr(profile, field) == Bounds(lower=lower, upper=upper)
