"""Alerts in the results database: fired once per event, delivered once, listed.

:func:`evaluate` checks the plant's rules (:mod:`station.domain.quality.alerts`) against
the stored runs: a rule whose condition holds and has no open alert fires one (``INSERT
… ON CONFLICT DO NOTHING``: the event key is unique, and a rule has at most one open
alert, so server processes evaluating at once store it once); one whose condition no
longer holds clears its open alert. :func:`claim_next` hands a process the next alert it
is to post, held for longer than a post takes (an ``UPDATE`` that only one process wins);
:func:`mark_delivered` records the webhook's acceptance, :func:`retry_later` a refusal
(tried again after the retry interval), the alert's row unchanged but for its attempts.
"""

from dataclasses import dataclass, replace
from datetime import datetime, timedelta
from itertools import pairwise
from statistics import fmean, stdev
from typing import Any

from sqlalchemy import ColumnElement, Row, func, select, update
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.orm import Session

from db.engine import for_dialect
from db.models import Run, RunFacts, StoredAlert
from db.rollups import PRODUCTION
from db.store.limits_profiles import stored_profiles
from db.store.outbox_reports import latest_outboxes
from station.domain.quality.alerts import (
    Alert,
    AlertRules,
    CpkRule,
    OutboxRule,
    ParameterWindow,
    RuleKind,
    SilentRule,
    WesternElectricRule,
    YieldRule,
)
from station.domain.quality.capability import D2, cpk
from station.domain.quality.control import western_electric
from station.domain.quality.parameters import PARAMETERS, profile_bounds

_INSERT = {
    name: dialect.insert(StoredAlert).on_conflict_do_nothing()
    for name, dialect in (("postgresql", postgresql), ("sqlite", sqlite))
}


@dataclass(frozen=True)
class _Check:
    """A rule checked now: its kind, scope and identity (``watch``: its kind, scope and
    thresholds; another goal is another rule), and its evidence and message if it holds."""

    rule: RuleKind
    scope: str
    watch: str
    evidence: dict[str, Any] | None = None
    message: str = ""
    #: What names the event among the rule's: the run that tipped it.
    tipped_by: str = ""


def _yield_check(session: Session, rule: YieldRule) -> _Check:
    """The first attempts of the last ``units`` units of one product (the product of the
    latest of them, at the rule's station or anywhere) and their first-pass yield, below
    the goal or not. A first attempt is the yield definition's (:mod:`db.rollups`): a
    production run, the unit's first that the operator did not abort."""
    check = _Check("yield", rule.scope, f"yield:{rule.scope}:{rule.units}:{rule.goal}")
    scope: list[ColumnElement[bool]] = [RunFacts.line_first.is_(True), PRODUCTION]
    if rule.station is not None:
        scope.append(Run.station_id == rule.station)
    latest = (Run.started_at.desc(), Run.id.desc())
    first = select(Run).join(RunFacts, RunFacts.run_pk == Run.id).where(*scope)
    # One product's units: a yield over two products would mix two processes.
    product = first.with_only_columns(Run.part_number).order_by(*latest).limit(1)
    stmt = (
        first.with_only_columns(Run.run_id, Run.serial, Run.started_at, Run.verdict)
        .where(Run.part_number == product.scalar_subquery())
        .order_by(*latest)
        .limit(rule.units)
    )
    rows = session.execute(stmt).all()
    passed = sum(row.verdict == "pass" for row in rows)
    if len(rows) < rule.units or passed / rule.units >= rule.goal:
        return check
    part_number = session.scalar(product)
    evidence = {
        "units": rule.units,
        "passed": passed,
        "first_pass_yield": passed / rule.units,
        "goal": rule.goal,
        "station": rule.station,
        "part_number": part_number,
        "since": min(row.started_at for row in rows).isoformat(),
        "failed": [row.serial for row in rows if row.verdict != "pass"],
    }
    message = (
        f"first-pass yield {passed / rule.units:.1%} of the last {rule.units} {part_number} "
        f"units at {rule.scope}, below the goal {rule.goal:.1%}"
    )
    return replace(check, evidence=evidence, message=message, tipped_by=str(rows[0].run_id))


def _silent_check(session: Session, rule: SilentRule, now: datetime) -> _Check:
    """The station's last run, if it started longer than ``minutes`` ago."""
    check = _Check("silent", rule.scope, f"silent:{rule.scope}:{rule.minutes}")
    last = session.execute(
        select(Run.run_id, Run.serial, Run.started_at)
        .where(Run.station_id == rule.station)
        .order_by(Run.started_at.desc(), Run.id.desc())
        .limit(1)
    ).first()
    if last is None or now - last.started_at < timedelta(minutes=rule.minutes):
        return check
    silent = (now - last.started_at).total_seconds() / 60
    evidence = {
        "station": rule.station,
        "minutes": rule.minutes,
        "since": last.started_at.isoformat(),
        "last_serial": last.serial,
        "silent_minutes": round(silent, 1),
    }
    message = f"no run from {rule.station} for {silent:.0f} min (rule: {rule.minutes:g} min)"
    return replace(check, evidence=evidence, message=message, tipped_by=str(last.run_id))


def _latest_values(session: Session, rule: ParameterWindow) -> list[Row[Any]]:
    """The last ``runs`` production runs with the rule's coefficient (at its station) of
    the product of the latest of them, oldest first: run id, serial, start, limits
    profile and ``value``."""
    column = getattr(Run, rule.parameter)
    scope = [column.is_not(None), Run.purpose.is_(None)]
    if rule.station is not None:
        scope.append(Run.station_id == rule.station)
    latest = (Run.started_at.desc(), Run.id.desc())
    # One product's runs: a line building two sensors (zero g 2048 and 32768 counts) would
    # otherwise judge both against one profile.
    product = select(Run.part_number).where(*scope).order_by(*latest).limit(1).scalar_subquery()
    stmt = (
        select(Run.run_id, Run.serial, Run.started_at, Run.limits_sha256, column.label("value"))
        .where(*scope, Run.part_number.is_not_distinct_from(product))
        .order_by(*latest)
        .limit(rule.runs)
    )
    return list(reversed(session.execute(stmt).all()))


def _cpk_check(session: Session, rule: CpkRule) -> _Check:
    """The Cpk of the last ``runs`` runs' ``parameter`` against the limits profile of the
    latest of them (mean and sample sd of those values), below the target or not."""
    check = _Check(
        "cpk", rule.scope, f"cpk:{rule.scope}:{rule.parameter}:{rule.runs}:{rule.target}"
    )
    rows = _latest_values(session, rule)
    if len(rows) < rule.runs:
        return check
    latest = rows[-1]
    profile = stored_profiles(session, [latest.limits_sha256]).get(latest.limits_sha256)
    if profile is None:  # a run from before stored profiles: no limits to judge by
        return check
    family = next(spec.family for spec in PARAMETERS if spec.name == rule.parameter)
    lower, upper = profile_bounds(profile)[family]
    values = [float(row.value) for row in rows]
    mean, sd = fmean(values), stdev(values)
    value = cpk(mean, sd, lower, upper)
    if value is None or value >= rule.target:
        return check
    evidence = {
        "parameter": rule.parameter,
        "station": rule.station,
        "runs": len(rows),
        "cpk": value,
        "target": rule.target,
        "mean": mean,
        "sd": sd,
        "lower": lower,
        "upper": upper,
        "limits": f"{profile.name} v{profile.version}",
        "since": rows[0].started_at.isoformat(),
    }
    message = (
        f"Cpk of {rule.parameter} {value:.2f} over the last {len(rows)} runs at {rule.scope}, "
        f"below the target {rule.target:g}"
    )
    return replace(check, evidence=evidence, message=message, tipped_by=str(latest.run_id))


def _western_electric_check(session: Session, rule: WesternElectricRule) -> _Check:
    """The last ``runs`` production runs' ``parameter`` as an individuals chart (centre
    x̄, σ = MR̄/d₂ of those runs, Montgomery's I-MR chart): whether the latest completes a
    Western Electric rule."""
    check = _Check(
        "western_electric",
        rule.scope,
        f"western_electric:{rule.scope}:{rule.parameter}:{rule.runs}",
    )
    rows = _latest_values(session, rule)
    if len(rows) < 2:
        return check
    values = [float(row.value) for row in rows]
    centre = sum(values) / len(values)
    mr_bar = sum(abs(b - a) for a, b in pairwise(values)) / (len(values) - 1)
    sigma = mr_bar / D2
    rules = western_electric(values, centre, sigma)[-1]
    if not rules:
        return check
    latest = rows[-1]
    evidence = {
        "parameter": rule.parameter,
        "station": rule.station,
        "runs": len(rows),
        "rules": rules,
        "value": values[-1],
        "centre": centre,
        "sigma": sigma,
        "serial": latest.serial,
        "since": rows[0].started_at.isoformat(),
    }
    message = (
        f"{rule.parameter} of {latest.serial} at {rule.scope} completes Western Electric "
        f"rule {', '.join(map(str, rules))} (x̄ {centre:.4g}, σ {sigma:.3g}, last {len(rows)} runs)"
    )
    return replace(check, evidence=evidence, message=message, tipped_by=str(latest.run_id))


def _outbox_checks(session: Session, rule: OutboxRule) -> list[_Check]:
    """Per station (the rule's, or each that reported), its latest outbox report: at
    least ``queued`` runs waiting, the oldest waiting ``hours`` or more, or a file set
    aside."""
    checks = []
    for report in latest_outboxes(session, rule.station):
        station = report.station_id
        check = _Check("outbox", station, f"outbox:{station}:{rule.queued}:{rule.hours}")
        waited_h = report.oldest_s / 3600
        reasons = [
            *([f"{report.queued} runs queued"] if report.queued >= rule.queued else []),
            *([f"the oldest waiting {waited_h:.1f} h"] if waited_h >= rule.hours else []),
            *([f"{report.set_aside} files set aside"] if report.set_aside else []),
        ]
        if reasons:
            evidence = {
                "station": station,
                "queued": report.queued,
                "oldest_s": report.oldest_s,
                "set_aside": report.set_aside,
                "reported_at": report.reported_at.isoformat(),
                "rule_queued": rule.queued,
                "rule_hours": rule.hours,
            }
            message = (
                f"outbox of {station}: {', '.join(reasons)} (rule: {rule.queued} runs, "
                f"{rule.hours:g} h, no file set aside)"
            )
            tipped_by = report.reported_at.isoformat()
            check = replace(check, evidence=evidence, message=message, tipped_by=tipped_by)
        checks.append(check)
    return checks


def evaluate(session: Session, rules: AlertRules, now: datetime) -> None:
    """Fire the alerts whose rule holds and has none open; clear those that no longer
    hold."""
    checks = [
        *(_yield_check(session, rule) for rule in rules.yield_rules),
        *(_silent_check(session, rule, now) for rule in rules.silent_rules),
        *(_western_electric_check(session, rule) for rule in rules.western_electric_rules),
        *(_cpk_check(session, rule) for rule in rules.cpk_rules),
        *(check for rule in rules.outbox_rules for check in _outbox_checks(session, rule)),
    ]
    for check in checks:
        open_alert = session.scalars(
            select(StoredAlert.id).where(
                StoredAlert.watch == check.watch, StoredAlert.cleared_at.is_(None)
            )
        ).first()
        if check.evidence is None and open_alert is not None:
            session.execute(
                update(StoredAlert).where(StoredAlert.id == open_alert).values(cleared_at=now)
            )
        elif check.evidence is not None and open_alert is None:
            # The rule's events so far (all cleared) and the run that tipped it: every
            # process that sees this event names it so, and a recurrence tipped by the
            # same run (late runs cleared it, then made it hold again) is a new event.
            earlier = session.scalar(
                select(func.count())
                .select_from(StoredAlert)
                .where(StoredAlert.watch == check.watch)
            )
            session.execute(
                for_dialect(session, _INSERT),
                {
                    "event_key": f"{check.watch}:{earlier}:{check.tipped_by}",
                    "watch": check.watch,
                    "rule": check.rule,
                    "scope": check.scope,
                    "message": check.message,
                    "evidence": check.evidence,
                    "fired_at": now,
                    "attempts": 0,
                    "next_attempt_at": now,
                },
            )


def _alert(row: StoredAlert) -> Alert:
    return Alert.model_validate({name: getattr(row, name) for name in Alert.model_fields})


def claim_next(session: Session, due_by: datetime, now: datetime, hold: timedelta) -> Alert | None:
    """The next undelivered alert due by ``due_by`` that this process won, held until
    ``now + hold`` (no other process posts it meanwhile: ``hold`` outlasts a post) with
    its attempt counted; None when none is left."""
    due = session.scalars(
        select(StoredAlert.id)
        .where(StoredAlert.delivered_at.is_(None), StoredAlert.next_attempt_at <= due_by)
        .order_by(StoredAlert.id)
    ).all()
    for alert_id in due:
        claimed = session.connection().execute(
            update(StoredAlert)
            .where(
                StoredAlert.id == alert_id,
                StoredAlert.delivered_at.is_(None),
                StoredAlert.next_attempt_at <= due_by,
            )
            .values(next_attempt_at=now + hold, attempts=StoredAlert.attempts + 1)
        )
        if claimed.rowcount == 1:
            return _alert(session.get_one(StoredAlert, alert_id))
    return None


def retry_later(session: Session, event_key: str, at: datetime) -> None:
    """The webhook did not take the alert ``event_key``: try again ``at``."""
    session.execute(
        update(StoredAlert)
        .where(StoredAlert.event_key == event_key, StoredAlert.delivered_at.is_(None))
        .values(next_attempt_at=at)
    )


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
