"""Each unit's stored answer equals the one its history gives, whatever order runs arrive in
(each later run updating the stored answer, each late one rebuilding it)."""

import uuid
from datetime import timedelta

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from sqlalchemy import delete, select
from sqlalchemy.orm import Session

from db import Database, RunRepository
from db.models import Run, Unit
from db.store.units import answer_json
from tests.conftest import examples
from tests.databases import rolled_back
from tests.db.records import OUTCOMES, T0, make_record

#: One submission: which of three units, minutes after T0 (ties happen), its outcome.
submissions = st.lists(
    st.tuples(st.integers(0, 2), st.integers(0, 4), st.sampled_from(sorted(OUTCOMES))),
    min_size=1,
    max_size=12,
)


def units_of(session: Session, serials: set[str]) -> dict[str, tuple[int, str]]:
    """The stored ``units`` rows of ``serials``: run key and answer."""
    rows = session.execute(
        select(Unit.serial, Unit.run_pk, Unit.calibration).where(Unit.serial.in_(serials))
    )
    return {serial: (run_pk, calibration) for serial, run_pk, calibration in rows}


@settings(
    max_examples=examples(30),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
@given(submissions)
def test_the_stored_state_is_the_latest_run_in_any_arrival_order(
    migrated_database: Database, arrivals: list[tuple[int, int, str]]
) -> None:
    prefix = f"PT-{uuid.uuid4().hex[:8]}-"
    with rolled_back(migrated_database) as session:
        repo = RunRepository(session)
        for unit, minute, outcome in arrivals:
            repo.submit(
                make_record(
                    serial=f"{prefix}{unit}",
                    started_at=T0 + timedelta(minutes=minute),
                    sensitivity=(813.95 + minute, 815.66, 820.17 + unit),
                    **OUTCOMES[outcome],
                )
            )
        serials = {f"{prefix}{unit}" for unit, _, _ in arrivals}
        stored = units_of(session, serials)
        # The definition: the answer of the unit's runs by (started_at, id), read from runs.
        for serial in serials:
            latest = repo.latest_for_serial(serial)
            assert latest is not None
            latest_pk = session.scalars(select(Run.id).where(Run.run_id == latest.run_id)).one()
            assert stored[serial] == (latest_pk, answer_json(repo.history(serial)))
        # Rebuilt from runs alone (the migration's and a bulk load's path): the same rows.
        session.execute(delete(Unit).where(Unit.serial.in_(serials)))
        repo.refresh_units()
        assert units_of(session, serials) == stored


def test_a_late_older_run_leaves_the_current_state_alone(session: Session) -> None:
    repo = RunRepository(session)
    retest = make_record(verdict="pass", started_at=T0 + timedelta(hours=1))
    first = make_record(verdict="fail", started_at=T0)
    repo.submit(retest)
    repo.submit(first)  # delivered late by the station's outbox
    (calibration,) = units_of(session, {retest.serial}).values()
    assert f'"run_id":"{retest.run_id}"' in calibration[1]
    assert '"verdict":"pass"' in calibration[1]
