"""The run's state machine: every phase is reachable, every run can end, the end is final."""

import pytest

from station.run.phases import TRANSITIONS, Phase, PhaseError, advance


def reachable(start: Phase) -> set[Phase]:
    seen, todo = {start}, [start]
    while todo:
        for nxt in TRANSITIONS[todo.pop()]:
            if nxt not in seen:
                seen.add(nxt)
                todo.append(nxt)
    return seen


def test_every_phase_is_reachable_from_the_first_pose() -> None:
    assert reachable(Phase.POSE) == set(Phase)


@pytest.mark.parametrize("phase", [p for p in Phase if p is not Phase.DONE])
def test_every_phase_can_end_in_a_verdict(phase: Phase) -> None:
    assert Phase.VERDICT in TRANSITIONS[phase] or phase is Phase.VERDICT
    assert Phase.DONE in reachable(phase)


def test_done_is_final_and_only_the_verdict_leads_there() -> None:
    assert not TRANSITIONS[Phase.DONE]
    assert [p for p in Phase if Phase.DONE in TRANSITIONS[p]] == [Phase.VERDICT]


def test_a_move_the_table_does_not_list_is_refused() -> None:
    assert advance(Phase.POSE, Phase.SOLVE) is Phase.SOLVE
    with pytest.raises(PhaseError, match="from unit_output to pose"):
        advance(Phase.UNIT_OUTPUT, Phase.POSE)
