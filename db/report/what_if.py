"""What-if limits: the runs of a report re-judged against a candidate limits profile.

Nothing is written: each run's stored values (pose noise, coefficients, verification
error, gyro bias, the coefficients' uncertainties, so a candidate with the guarded
decision rule can be compared with the simple one) and stored failures are read a page
at a time and judged again by :func:`station.domain.product.judging.rejudge`, the
station's own checks. What the report needs is counted on the way: the runs that pass,
the units whose first attempt on the line is in range (the report's cohort, by the yield
definition of :mod:`db.rollups`) with their first and final passes — a unit's latest
attempt may lie after the range, so those runs are judged too — the failing runs by
their new first failure reason, the verdicts that change, and the cohort's units whose
latest attempt's verdict flips.
"""

from collections import Counter
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any

from sqlalchemy import ColumnElement, Row, and_, select, tuple_
from sqlalchemy.orm import Session

from db.models import Run, RunFacts, RunPose
from db.store.mapping import failure_reason, failures_of, stored_axes
from station.domain.product.judging import Measured, rejudge
from station.domain.product.limits import LimitsProfile
from station.domain.quality.figures import VerdictFlip
from station.domain.record.records import FailureReason

#: Runs judged per page.
PAGE = 2000
#: The most flipped units a what-if lists (the first by serial; all are counted).
LISTED_FLIPS = 200


@dataclass
class Rejudged:
    """The counts of the runs in range under the candidate profile."""

    runs: int = 0
    runs_passed: int = 0
    units: int = 0
    first_pass: int = 0
    final_pass: int = 0
    pass_to_fail: int = 0
    fail_to_pass: int = 0
    #: Failing runs per (first failure code, station, operator).
    failures: Counter[tuple[str, str, str]] = field(default_factory=Counter)
    #: The cohort's units whose latest attempt's verdict flips (the first by serial).
    flips: list[VerdictFlip] = field(default_factory=list)
    flips_total: int = 0


def _uncertainty(document: dict[str, Any] | None) -> dict[str, tuple[float, ...]]:
    """A stored run's U of its offsets, sensitivities, gyro biases and verification error
    (a candidate profile with the guarded rule judges by them; a run stored without them,
    by its values)."""
    if not document:
        return {}
    triples: dict[str, tuple[float, ...]] = {
        code: tuple(float(document[code][a]) for a in "xyz")
        for code in ("offset", "sensitivity")
        if code in document
    }
    if (bias := document.get("gyro_bias_dps")) is not None:
        triples["gyro_bias"] = tuple(float(bias[i]) for i in range(3))
    if (verification := document.get("verification_error_mg")) is not None:
        triples["verification_error"] = (float(verification),)
    return triples


@dataclass(frozen=True)
class _Judged:
    """A run as stored (``row``, its ``stored`` failures) and its ``failures`` under the
    candidate."""

    row: Row[Any]
    stored: list[FailureReason]
    failures: list[FailureReason]

    @property
    def passed_before(self) -> bool:
        return bool(self.row.verdict == "pass")

    @property
    def passed(self) -> bool:
        return not self.failures

    def flip(self) -> VerdictFlip | None:
        """The run's verdict flipping, if it does."""
        if self.passed == self.passed_before:
            return None
        deciding = self.stored if self.passed else self.failures
        return VerdictFlip(
            serial=self.row.serial,
            run_id=str(self.row.run_id),
            before="pass" if self.passed_before else "fail",
            after="pass" if self.passed else "fail",
            check=deciding[0].code if deciding else None,
        )


def _judged(
    session: Session, where: Sequence[ColumnElement[bool]], candidate: LimitsProfile
) -> Iterator[_Judged]:
    """Each run ``where`` selects, as stored and judged against ``candidate``; in start
    order, a page at a time."""
    columns = (
        Run.id,
        Run.run_id,
        Run.started_at,
        Run.serial,
        Run.verdict,
        Run.station_id,
        Run.operator_id,
        *(getattr(Run, f"{k}_{a}") for k in ("offset", "sensitivity") for a in "xyz"),
        Run.verification_error_mg,
        Run.uncertainty,
        *(getattr(RunFacts, f"gyro_bias_{a}") for a in "xyz"),
        RunFacts.line_first,
        RunFacts.line_latest,
    )
    after: tuple[Any, int] | None = None
    while True:
        stmt = (
            select(*columns)
            .join(RunFacts, RunFacts.run_pk == Run.id)
            .where(*where)
            .order_by(Run.started_at, Run.id)
            .limit(PAGE)
        )
        if after is not None:
            stmt = stmt.where(
                (Run.started_at > after[0]) | and_(Run.started_at == after[0], Run.id > after[1])
            )
        rows = list(session.execute(stmt).all())
        if not rows:
            return
        keys = [(row.id, row.started_at) for row in rows]
        poses: dict[int, list[Any]] = {}
        for pose in session.execute(
            select(
                RunPose.run_pk,
                RunPose.index.label("position"),
                RunPose.role,
                *(getattr(RunPose, f"std_{a}") for a in "xyz"),
            )
            .where(tuple_(RunPose.run_pk, RunPose.started_at).in_(keys))
            .order_by(RunPose.run_pk, RunPose.index)
        ):
            poses.setdefault(pose.run_pk, []).append(pose)
        failures = {
            pk: [failure_reason(f) for f in stored]
            for pk, stored in failures_of(session, [pk for pk, _ in keys]).items()
        }
        for row in rows:
            own = poses.get(row.id, [])
            verify = next((p.position for p in own if p.role == "verify"), None)
            error = row.verification_error_mg
            measured = Measured(
                pose_noise={p.position: (p.std_x, p.std_y, p.std_z) for p in own},
                offset=stored_axes(row, "offset"),
                sensitivity=stored_axes(row, "sensitivity"),
                verification=None if error is None or verify is None else (verify, error),
                gyro_bias=stored_axes(row, "gyro_bias"),
                uncertainty=_uncertainty(row.uncertainty),
            )
            stored = failures.get(row.id, [])
            yield _Judged(row, stored, rejudge(stored, candidate, measured))
        after = (rows[-1].started_at, rows[-1].id)


def rejudged(
    session: Session, where: Sequence[ColumnElement[bool]], candidate: LimitsProfile
) -> Rejudged:
    """The runs ``where`` selects (the report's range) re-judged against ``candidate``."""
    counts = Rejudged()
    cohort: set[str] = set()
    final: dict[str, _Judged] = {}
    for run in _judged(session, where, candidate):
        row, passed = run.row, run.passed
        counts.runs += 1
        counts.runs_passed += passed
        counts.pass_to_fail += run.passed_before and not passed
        counts.fail_to_pass += passed and not run.passed_before
        if run.failures:
            counts.failures[(run.failures[0].code, row.station_id, row.operator_id)] += 1
        if row.line_first:
            cohort.add(row.serial)
            counts.units += 1
            counts.first_pass += passed
        if row.line_latest:
            final[row.serial] = run
    # The cohort's latest attempts outside the selection (after the range, or of another
    # station, operator or lot); those in it are judged already.
    first_in_range = (
        select(Run.serial)
        .join(RunFacts, RunFacts.run_pk == Run.id)
        .where(RunFacts.line_first.is_(True), *where)
        .correlate(None)  # the runs of the range, not the outer query's run
    )
    latest = [RunFacts.line_latest.is_(True), Run.serial.in_(first_in_range)]
    for run in _judged(session, latest, candidate):
        final.setdefault(run.row.serial, run)
    counts.final_pass = sum(final[serial].passed for serial in cohort if serial in final)
    flips = [
        flip for serial in sorted(cohort) if serial in final and (flip := final[serial].flip())
    ]
    counts.flips, counts.flips_total = flips[:LISTED_FLIPS], len(flips)
    return counts
