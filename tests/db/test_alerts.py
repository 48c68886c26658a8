"""The alert rules against stored runs, one round at a time (`db.report.alerts.evaluate`): a
condition that clears and holds again is a new event even when the same run tips it,
and a rule over a coefficient judges the runs of one product."""

from datetime import UTC, datetime, timedelta

import numpy as np
from sqlalchemy import select

from db import Database, RunRepository
from db.models import StoredAlert
from db.report.alerts import evaluate
from station.domain.quality.alerts import parse_alert_rules
from tests.db.records import T0, make_record

#: Where the rules' alerts would go (no round here posts).
WEBHOOK = 'webhook = "http://127.0.0.1:9/hook"\n'
#: A round's clock: the runs below start a day before it.
NOW = datetime(2026, 11, 26, 12, tzinfo=UTC)


def _store(database: Database, *runs: tuple[str, float, str]) -> None:
    """Units at st1, each one run: (serial, its start in minutes from T0, verdict)."""
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        for serial, minute, verdict in runs:
            repository.submit(
                make_record(
                    serial=serial,
                    station_id="st1",
                    started_at=T0 + timedelta(minutes=minute),
                    verdict=verdict,
                )
            )


def _round(database: Database, rules: str) -> list[StoredAlert]:
    with database.session() as session, session.begin():
        evaluate(session, parse_alert_rules(rules, "rules"), NOW)
    with database.session() as session:
        return list(session.scalars(select(StoredAlert).order_by(StoredAlert.id)))


def test_a_yield_that_recovers_and_drops_again_by_late_runs_is_a_new_event(
    database: Database,
) -> None:
    rules = (
        'webhook = "http://127.0.0.1:9/hook"\n[[yield]]\nstation = "st1"\nunits = 4\ngoal = 0.75\n'
    )
    _store(database, ("PT0", 0, "pass"), ("PT1", 1, "fail"), ("PT2", 2, "pass"), ("PT3", 3, "fail"))
    (first,) = _round(database, rules)  # 2 of the last 4 passed: 50 % < 75 %
    # Two late passing units (their runs started before PT3's, which stays the newest):
    # PT3, LATE2, LATE1, PT2: 3 of 4, the alert clears.
    _store(database, ("LATE1", 2.5, "pass"), ("LATE2", 2.6, "pass"))
    (cleared,) = _round(database, rules)
    assert cleared.cleared_at is not None
    # Two late failing units: PT3, LATE4, LATE3, LATE2: 1 of 4, below again, and PT3 still
    # the newest: a new event all the same.
    _store(database, ("LATE3", 2.7, "fail"), ("LATE4", 2.8, "fail"))
    alerts = _round(database, rules)
    assert len(alerts) == 2
    assert alerts[0].event_key == first.event_key
    assert alerts[1].event_key != first.event_key
    assert alerts[1].cleared_at is None


def test_a_cpk_rule_judges_the_runs_of_the_latest_runs_product(database: Database) -> None:
    # Two products alternate at st1, their offsets 200 counts apart, each steady: over both
    # the spread would put Cpk far below 1.33; over the latest run's product it is high.
    rules = f'{WEBHOOK}[[cpk]]\nparameter = "offset_x"\nruns = 20\n'
    noise = np.random.default_rng(3).normal(0.0, 0.5, 40)
    with database.session() as session, session.begin():
        repository = RunRepository(session)
        for i in range(40):
            left = i % 2 == 0
            repository.submit(
                make_record(
                    serial=f"PT{i:04d}",
                    station_id="st1",
                    started_at=T0 + timedelta(minutes=i),
                    offset=(2150.0 + noise[i] if left else 1950.0 + noise[i], 2041.2, 1960.5),
                    part_number="DIXX-A12-LH" if left else "DIXX-A12",
                )
            )
    assert _round(database, rules) == []


def test_a_yield_rule_judges_the_first_attempts_of_the_latest_units_product(
    database: Database,
) -> None:
    """The last 4 units of both products would be 3 of 4 (75 % < 80 %); the A12 units'
    are 4 of 4, one of them passed at its first attempt after an aborted run. A D16 unit
    failing last turns the rule to the D16 units: 1 of 4."""
    rules = f"{WEBHOOK}[[yield]]\nunits = 4\ngoal = 0.8\n"
    plan = [
        ("D0", "DIXX-D16", "pass"),
        ("A0", "DIXX-A12", "pass"),
        ("D1", "DIXX-D16", "fail"),
        ("A1", "DIXX-A12", "aborted"),
        ("A1", "DIXX-A12", "pass"),
        ("D2", "DIXX-D16", "fail"),
        ("A2", "DIXX-A12", "pass"),
        ("A3", "DIXX-A12", "pass"),
    ]

    def store(*runs: tuple[str, str, str]) -> None:
        with database.session() as session, session.begin():
            repository = RunRepository(session)
            for minute, (serial, product, outcome) in enumerate(runs, len(stored)):
                code = "aborted" if outcome == "aborted" else "offset"
                repository.submit(
                    make_record(
                        serial=serial,
                        part_number=product,
                        station_id="st1",
                        started_at=T0 + timedelta(minutes=minute),
                        verdict="pass" if outcome == "pass" else "fail",
                        failures=[] if outcome == "pass" else [{"code": code, "message": "-"}],
                    )
                )
            stored.extend(runs)

    stored: list[tuple[str, str, str]] = []
    store(*plan)
    assert _round(database, rules) == []
    store(("D3", "DIXX-D16", "fail"))
    (alert,) = _round(database, rules)
    evidence = alert.evidence
    assert (evidence["part_number"], evidence["passed"]) == ("DIXX-D16", 1)
    assert sorted(evidence["failed"]) == ["D1", "D2", "D3"]
