"""A unit's answer kept up to date run by run equals the answer read from its whole history."""

from datetime import timedelta

from hypothesis import given, settings
from hypothesis import strategies as st

from station.domain.record.records import RunRecord
from station.domain.record.unit_state import UnitCalibration
from tests.conftest import examples
from tests.db.records import OUTCOMES, T0, make_record


def _history(outcomes: list[str]) -> list[RunRecord]:
    return [
        make_record(
            started_at=T0 + timedelta(minutes=i),
            sensitivity=(813.95 + i, 815.66, 820.17),
            disposition="ship" if outcome == "pass" else "retest",
            **OUTCOMES[outcome],
        )
        for i, outcome in enumerate(outcomes)
    ]


@settings(max_examples=examples(150), deadline=None)
@given(st.lists(st.sampled_from(sorted(OUTCOMES)), min_size=1, max_size=8))
def test_the_answer_updated_run_by_run_is_the_answer_of_the_history(outcomes: list[str]) -> None:
    runs = _history(outcomes)
    answer = UnitCalibration.of_history(runs[:1])
    for i, run in enumerate(runs[1:], start=2):
        # As stored between submissions: JSON text, read back.
        answer = UnitCalibration.model_validate_json(answer.model_dump_json()).then(run)
        assert answer == UnitCalibration.of_history(runs[:i])
