"""Alerts in the results database: fired once per event, delivered once, listed.

:func:`evaluate` checks the plant's rules (:mod:`station.domain.quality.alerts`) against
the stored runs: a rule whose condition holds and has no open alert fires one (``INSERT
… ON CONFLICT DO NOTHING``: the event key is unique, and a rule has at most one open
alert, so server processes evaluating at once store it once); one whose condition no
longer holds clears its open alert. :func:`claim_due` hands a process the alerts it is to
post, each held for the retry interval (an ``UPDATE`` that only one process wins), and
:func:`mark_delivered` records the webhook's acceptance; a refused post is tried again
once the hold ends, the alert's row unchanged but for its attempts.
"""

from datetime import datetime, timedelta
from typing import Any

from sqlalchemy import select, update
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.orm import Session

from db.engine import for_dialect
from db.models import Run, RunFacts, StoredAlert
from station.domain.quality.alerts import Alert, AlertRules, YieldRule

_INSERT = {
    name: dialect.insert(StoredAlert).on_conflict_do_nothing()
    for name, dialect in (("postgresql", postgresql), ("sqlite", sqlite))
}


def _watch(rule: YieldRule) -> str:
    """The rule's identity: its kind, scope and thresholds (another goal: another rule)."""
    return f"yield:{rule.scope}:{rule.units}:{rule.goal}"


def _yield_event(session: Session, rule: YieldRule) -> dict[str, Any] | None:
    """The evidence of ``rule`` holding now, or None: the first runs of the last
    ``units`` units (production runs, not golden-unit checks), their first-pass yield."""
    stmt = (
        select(Run.run_id, Run.serial, Run.started_at, Run.verdict)
        .join(RunFacts, RunFacts.run_pk == Run.id)
        .where(RunFacts.line_first.is_(True), Run.purpose.is_(None))
        .order_by(Run.started_at.desc(), Run.id.desc())
        .limit(rule.units)
    )
    if rule.station is not None:
        stmt = stmt.where(Run.station_id == rule.station)
    rows = session.execute(stmt).all()
    passed = sum(row.verdict == "pass" for row in rows)
    if len(rows) < rule.units or passed / rule.units >= rule.goal:
        return None
    return {
        "units": rule.units,
        "passed": passed,
        "first_pass_yield": passed / rule.units,
        "goal": rule.goal,
        "station": rule.station,
        "since": min(row.started_at for row in rows).isoformat(),
        "latest_run": str(rows[0].run_id),
        "failed": [row.serial for row in rows if row.verdict != "pass"],
    }


def evaluate(session: Session, rules: AlertRules, now: datetime) -> None:
    """Fire the alerts whose rule holds and has none open; clear those that no longer
    hold."""
    for rule in rules.yield_rules:
        watch = _watch(rule)
        evidence = _yield_event(session, rule)
        open_alert = session.scalars(
            select(StoredAlert.id).where(
                StoredAlert.watch == watch, StoredAlert.cleared_at.is_(None)
            )
        ).first()
        if evidence is None and open_alert is not None:
            session.execute(
                update(StoredAlert).where(StoredAlert.id == open_alert).values(cleared_at=now)
            )
        elif evidence is not None and open_alert is None:
            message = (
                f"first-pass yield {evidence['first_pass_yield']:.1%} of the last "
                f"{rule.units} units at {rule.scope}, below the goal {rule.goal:.1%}"
            )
            session.execute(
                for_dialect(session, _INSERT),
                {
                    # The run that tipped it: every process that sees the event names it so.
                    "event_key": f"{watch}:{evidence['latest_run']}",
                    "watch": watch,
                    "rule": "yield",
                    "scope": rule.scope,
                    "message": message,
                    "evidence": evidence,
                    "fired_at": now,
                    "attempts": 0,
                    "next_attempt_at": now,
                },
            )


def _alert(row: StoredAlert) -> Alert:
    return Alert(
        event_key=row.event_key,
        rule="yield",
        scope=row.scope,
        message=row.message,
        fired_at=row.fired_at,
        cleared_at=row.cleared_at,
        delivered_at=row.delivered_at,
        attempts=row.attempts,
        evidence=row.evidence,
    )


def claim_due(session: Session, now: datetime, hold: timedelta) -> list[Alert]:
    """The undelivered alerts due now that this process won, each held for ``hold``
    (no other process posts it meanwhile) and its attempt counted."""
    due = session.scalars(
        select(StoredAlert.id)
        .where(StoredAlert.delivered_at.is_(None), StoredAlert.next_attempt_at <= now)
        .order_by(StoredAlert.id)
    ).all()
    won = []
    for alert_id in due:
        claimed = session.connection().execute(
            update(StoredAlert)
            .where(
                StoredAlert.id == alert_id,
                StoredAlert.delivered_at.is_(None),
                StoredAlert.next_attempt_at <= now,
            )
            .values(next_attempt_at=now + hold, attempts=StoredAlert.attempts + 1)
        )
        if claimed.rowcount == 1:
            won.append(alert_id)
    rows = session.scalars(select(StoredAlert).where(StoredAlert.id.in_(won))).all()
    return [_alert(row) for row in rows]


def mark_delivered(session: Session, event_key: str, now: datetime) -> None:
    """The webhook took the alert ``event_key``."""
    session.execute(
        update(StoredAlert).where(StoredAlert.event_key == event_key).values(delivered_at=now)
    )


def recent_alerts(session: Session, limit: int) -> list[Alert]:
    """The latest ``limit`` alerts, the newest first."""
    rows = session.scalars(
        select(StoredAlert)
        .order_by(StoredAlert.fired_at.desc(), StoredAlert.id.desc())
        .limit(limit)
    ).all()
    return [_alert(row) for row in rows]
