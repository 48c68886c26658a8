"""A failure's explanation in Korean and Chinese, rendered from the stored code and
parameters: no English word of the operator's left, every value, bound, axis and pose
kept, no placeholder left unfilled; English is the stored sentence itself."""

import math
import re

import pytest
from hypothesis import given
from hypothesis import strategies as st

from station.domain.calibration import CalibrationError
from station.domain.product.limits import CHECKS, Bounds, check, load_profile
from station.domain.record.records import FailureReason
from station.report.explanations import explanation
from station.run.verdict import (
    Failures,
    calibration_failed,
    gyro_matrix_failed,
    saturated,
    verification_move_failed,
    writeback_failed,
)

TRANSLATED = ("ko", "zh")
#: Latin words a translation keeps: a unit symbol and the converter's acronym.
KEPT = {"mg", "ADC"}
WORD = re.compile(r"[A-Za-z]{2,}")


def english_words(text: str) -> set[str]:
    """The Latin words of ``text`` that are not symbols every language writes alike."""
    return set(WORD.findall(text)) - KEPT


@st.composite
def limit_failures(draw: st.DrawFn) -> FailureReason:
    """A limit check as :func:`station.domain.product.limits.check` records it when it fails: a
    value outside its bounds (simple rule), or inside them by less than its U (guarded),
    or not a number."""
    code = draw(st.sampled_from(sorted(CHECKS)))
    lower = draw(st.floats(-1e4, 1e4))
    upper = lower + draw(st.floats(1e-3, 1e4))
    side = draw(st.sampled_from(["both", "lower", "upper"]))
    bounds = Bounds(
        lower=None if side == "upper" else lower, upper=None if side == "lower" else upper
    )
    kind = draw(st.sampled_from(["outside", "guarded", "not finite"]))
    margin = draw(st.floats(1e-3, 1e3))
    uncertainty = None
    if kind == "not finite":
        measured = math.nan
    elif kind == "outside":
        measured = upper + margin if side != "lower" else lower - margin
    else:  # inside, nearer its bound than its U
        measured = upper - margin / 2 if side != "lower" else lower + margin / 2
        uncertainty = margin
    rule = "guarded" if kind == "guarded" else "simple"
    profile = load_profile().model_copy(update={CHECKS[code]: bounds, "decision_rule": rule})
    failure = check(
        profile,
        code,
        measured,
        axis=draw(st.sampled_from([None, "x", "y", "z"])),
        pose=draw(st.none() | st.integers(0, 8)),
        uncertainty=uncertainty,
    )
    assert failure is not None  # the generator makes failing checks only
    return failure


@given(failure=limit_failures(), language=st.sampled_from(TRANSLATED))
def test_a_failed_limit_check_reads_in_the_operators_language(
    failure: FailureReason, language: str
) -> None:
    text = explanation(failure, language)
    assert not english_words(text), (text, failure.message)
    assert not set("{}") & set(text)
    bounds = Bounds(lower=failure.lower, upper=failure.upper)
    assert bounds.describe() in text
    if failure.measured is not None:
        assert f"{failure.measured:.6g}" in text
        if bounds.contains(failure.measured):  # refused by the guard band: U is stored
            assert failure.uncertainty is not None
            assert f"U = {failure.uncertainty:.3g}" in text
    if failure.axis is not None:
        assert f" {failure.axis}" in text
    if failure.pose is not None:
        assert str(failure.pose + 1) in text
    assert explanation(failure, "en") == failure.message


def _found() -> list[FailureReason]:
    """Every failure a run finds while it goes (:mod:`station.run.verdict`)."""
    written, before = Failures(), Failures()
    written.abort(written=True)
    before.abort(written=False)
    return [
        saturated(("x",), 2),
        saturated(("x", "z"), 0),
        calibration_failed(CalibrationError("the poses do not span the sphere", pose=3)),
        calibration_failed(CalibrationError("fewer poses than the model needs")),
        writeback_failed(OSError("timeout waiting for ACK")),
        gyro_matrix_failed(ValueError("move 2: too short")),
        verification_move_failed("no rotation seen"),
        *written.found,
        *before.found,
    ]


@pytest.mark.parametrize("language", TRANSLATED)
@pytest.mark.parametrize("failure", _found(), ids=lambda f: f"{f.code}-{f.pose}-{f.axis}")
def test_a_failure_found_while_the_run_went_reads_in_the_operators_language(
    failure: FailureReason, language: str
) -> None:
    text = explanation(failure, language)
    assert not english_words(text), (text, failure.message)
    assert not set("{}") & set(text)
    if failure.pose is not None:
        assert str(failure.pose + 1) in text
    if failure.axis is not None:
        assert failure.axis in text
    assert explanation(failure, "en") == failure.message


@pytest.mark.parametrize("language", TRANSLATED)
def test_an_unknown_code_is_named_as_stored(language: str) -> None:
    failure = FailureReason(code="torque_spike", message="torque spiked to 9 N·m")
    text = explanation(failure, language)
    assert "torque_spike" in text
    assert english_words(text) == {"torque", "spike"}  # the code's own letters only
