"""Queries of the results database: submit runs, read a unit's state and history, list runs.

Every query is one indexed SQL statement (no scan in Python): a unit's latest run walks
``ix_runs_serial_started_at`` backwards, lists walk the index that matches their filter
with keyset (cursor) pagination on ``(started_at, id)``.
"""

import base64
import binascii
import hashlib
import secrets
from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from typing import Any, Literal, TypeVarTuple, cast
from uuid import UUID

from sqlalchemy import ColumnElement, Select, insert, select, text, tuple_, update
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.orm import Session
from sqlalchemy.sql.dml import ReturningInsert

from db.base import Base
from db.engine import for_dialect
from db.models import (
    GyroFit,
    Run,
    RunFailure,
    RunId,
    RunPose,
    StationKey,
    StoredLimitsProfile,
)
from db.models import (
    HoldReview as ReviewRow,
)
from db.rollups import lock_submissions, record_run
from db.store.limits_profiles import store_profile
from db.store.mapping import failure_rows, failures_of, pose_row, run_row, stored_run_of, summary_of
from db.store.outbox_reports import record_outbox
from db.store.units import record_unit_run, refresh_answers
from station.domain.constants import DEFAULT_PART_NUMBER
from station.domain.errors import CalstationError, InputError
from station.domain.record.outbox_report import OutboxReport
from station.domain.record.records import (
    GyroFitRecord,
    HoldReview,
    RunRecord,
    RunSummary,
    StoredRun,
    Verdict,
)

# Core tables for the bulk inserts of a submission (lighter than the ORM's bulk path).
_POSES = Base.metadata.tables[RunPose.__tablename__]
_FAILURES = Base.metadata.tables[RunFailure.__tablename__]

# Built once, values bound at execution: the compiled statement is cached.
_REGISTER_RUN: dict[str, ReturningInsert[int]] = {
    name: dialect.insert(RunId)
    .on_conflict_do_nothing(index_elements=["run_id"])
    .returning(RunId.run_pk)
    for name, dialect in (("postgresql", postgresql), ("sqlite", sqlite))
}

Ts = TypeVarTuple("Ts")

#: Largest page of a run list.
MAX_PAGE = 500


class RunConflictError(CalstationError):
    """A run with this UUID is already stored with different content."""


#: What an API key may store: its station's runs, units' gyro fits (a lab's) or reviews.
KeyScope = Literal["station", "lab", "quality"]


@dataclass(frozen=True)
class KeyHolder:
    """The station or lab a key belongs to (``holder``) and what it may store."""

    holder: str
    scope: KeyScope


@dataclass(frozen=True)
class SubmitOutcome:
    """What a submission did: stored a new run, or found the same run already stored."""

    created: bool
    run: StoredRun


@dataclass(frozen=True)
class RunQuery:
    """Filters of a run list; ``since`` inclusive, ``until`` exclusive, on ``started_at``."""

    serial: str | None = None
    station_id: str | None = None
    lot: str | None = None
    part_number: str | None = None
    verdict: Verdict | None = None
    since: datetime | None = None
    until: datetime | None = None
    limit: int = 100
    cursor: str | None = None


@dataclass(frozen=True)
class RunPage:
    """One page of a run list, newest first; ``next_cursor`` is ``None`` on the last page."""

    runs: list[RunSummary]
    next_cursor: str | None


def _by_run_id(query: Select[*Ts], run_id: UUID) -> Select[*Ts]:
    """``query`` of ``runs`` narrowed to the run ``run_id``, found in the register: by its
    key and its start, so that PostgreSQL reads one year's partition."""
    return query.join(RunId, (RunId.run_pk == Run.id) & (RunId.started_at == Run.started_at)).where(
        RunId.run_id == run_id
    )


#: The record's optional fields added after the first stations shipped.
_ADDED_FIELDS = (
    "lot",
    "disposition",
    "purpose",
    "gyro_matrix",
    "uncertainty",
    "decision_rule",
    "as_found",
)


def record_sha256(record: RunRecord) -> str:
    """SHA-256 of the record's canonical JSON: equal for a retry, different for a clash.

    A record without a lot, a disposition, a purpose, a gyro matrix, uncertainties, a
    decision rule, its as-found values, its limits profile or excluded poses, or of the
    default product, is hashed without the field, as before the field existed, so a retry
    from an older station matches the run it stored.
    """
    unset: dict[str, Any] = {name: True for name in _ADDED_FIELDS if getattr(record, name) is None}
    if record.part_number == DEFAULT_PART_NUMBER:  # every run before products existed
        unset["part_number"] = True
    if record.limits.profile is None:
        unset["limits"] = {"profile"}
    if record.quality is not None and record.quality.excluded_poses is None:
        unset["quality"] = {"excluded_poses"}
    return hashlib.sha256(record.model_dump_json(exclude=unset or None).encode()).hexdigest()


def key_sha256(key: str) -> str:
    """How an API key is stored: its SHA-256 (keys are 256-bit random, not passwords)."""
    return hashlib.sha256(key.encode()).hexdigest()


def encode_cursor(started_at: datetime, pk: int) -> str:
    """An opaque cursor pointing just past the run ``(started_at, pk)``."""
    raw = f"{started_at.astimezone(UTC).isoformat()}|{pk}".encode()
    return base64.urlsafe_b64encode(raw).decode().rstrip("=")


def decode_cursor(cursor: str) -> tuple[datetime, int]:
    """Undo :func:`encode_cursor`; :class:`InputError` for anything else."""
    try:
        raw = base64.urlsafe_b64decode(cursor + "=" * (-len(cursor) % 4)).decode()
        moment, pk = raw.split("|")
        started_at, run_pk = datetime.fromisoformat(moment), int(pk)
        if started_at.tzinfo is None or not 0 < run_pk < 2**63:
            raise ValueError("not a cursor")
        return started_at.astimezone(UTC), run_pk
    except (ValueError, OverflowError, binascii.Error, UnicodeDecodeError):
        raise InputError(f"cursor {cursor[:40]!r} is not one this server handed out") from None


class RunRepository:
    """Runs, API keys and gyro fits, in the caller's session (the caller commits)."""

    def __init__(self, session: Session) -> None:
        self.session = session

    def ping(self) -> str:
        """Raise if the database does not answer; return its dialect's name."""
        self.session.execute(text("SELECT 1"))
        return self.session.get_bind().dialect.name

    # -- runs --------------------------------------------------------------------------

    def submit(
        self,
        record: RunRecord,
        *,
        received_at: datetime | None = None,
        outbox: OutboxReport | None = None,
    ) -> SubmitOutcome:
        """Store ``record`` unless a run with its UUID is stored already.

        The register's unique ``run_id`` decides (``INSERT … ON CONFLICT DO NOTHING``
        into ``run_ids``, which numbers the run), so concurrent duplicates cannot both
        land. A retry of the same record returns the stored run; the same UUID with other
        content raises :class:`RunConflictError`. A new run brings the report's facts and
        roll-ups up to date in the same transaction (:func:`db.rollups.record_run`);
        submissions are serialised for that (:func:`db.rollups.lock_submissions`).
        ``outbox``: the station's outbox as it sent the run, kept as its latest report
        (:func:`db.store.outbox_reports.record_outbox`), a retry's too.
        """
        digest = record_sha256(record)
        received_at = received_at or datetime.now(UTC)
        lock_submissions(self.session.connection())
        pk = self.session.execute(
            for_dialect(self.session, _REGISTER_RUN),
            {"run_id": record.run_id, "started_at": record.started_at},
        ).scalar_one_or_none()
        if outbox is not None:
            record_outbox(self.session, record.station_id, outbox, received_at)
        if pk is None:
            stored_digest = self.session.scalars(
                _by_run_id(select(Run.record_sha256), record.run_id)
            ).one()
            if stored_digest != digest:
                raise RunConflictError(
                    f"run {record.run_id} is already stored with different content"
                )
            stored = self.get(record.run_id)
            assert stored is not None
            return SubmitOutcome(created=False, run=stored)
        self.session.execute(
            insert(Run), run_row(record, pk=pk, received_at=received_at, record_sha256=digest)
        )
        store_profile(self.session, record.limits)
        self.session.execute(
            insert(_POSES), [pose_row(pk, record.started_at, pose) for pose in record.poses]
        )
        if record.failures:
            self.session.execute(insert(_FAILURES), failure_rows(pk, record))
        record_run(self.session.connection(), pk)
        # Already validated: build the answer without validating it again.
        stored = StoredRun.model_construct(**dict(record), received_at=received_at)
        record_unit_run(self.session, pk, stored)
        return SubmitOutcome(created=True, run=stored)

    def get(self, run_id: UUID) -> StoredRun | None:
        """One run with its poses and failure reasons."""
        run = self.session.scalars(_by_run_id(select(Run), run_id)).one_or_none()
        if run is None:
            return None
        poses = self.session.scalars(
            select(RunPose)
            .where(RunPose.run_pk == run.id, RunPose.started_at == run.started_at)
            .order_by(RunPose.index)
        ).all()
        profile = self.session.get(StoredLimitsProfile, run.limits_sha256)
        document = None if profile is None else profile.document
        return stored_run_of(
            run, failures_of(self.session, [run.id])[run.id], list(poses), document
        )

    def latest_for_serial(self, serial: str) -> RunSummary | None:
        """The unit's current state: its latest run (by start time)."""
        return self._latest(Run.serial == serial)

    def history(self, serial: str) -> list[RunSummary]:
        """Every run of the unit, oldest first (the first one gives first-pass yield)."""
        runs = self.session.scalars(
            select(Run).where(Run.serial == serial).order_by(Run.started_at, Run.id)
        ).all()
        return self._summaries(runs)

    def latest_golden(
        self, station_id: str, since: datetime, before: datetime
    ) -> RunSummary | None:
        """The latest golden-unit run (``purpose`` golden) of ``station_id`` started in
        ``[since, before)``: the shift's check a certificate names as its reference."""
        return self._latest(
            Run.station_id == station_id,
            Run.purpose == "golden",
            Run.started_at >= since,
            Run.started_at < before,
        )

    def serials(self, prefix: str, limit: int | None = None) -> list[str]:
        """The serial numbers stored that begin with ``prefix`` (its ``_`` and ``%`` as
        themselves), in order; the first ``limit`` of them. A walk of
        ``ix_runs_serial_started_at`` from ``prefix``."""
        stmt = (
            select(Run.serial)
            .where(Run.serial.startswith(prefix, autoescape=True))
            .distinct()
            .order_by(Run.serial)
            .limit(limit)
        )
        return list(self.session.scalars(stmt))

    def list_runs(self, query: RunQuery) -> RunPage:
        """A page of runs matching ``query``, newest first."""
        if not 1 <= query.limit <= MAX_PAGE:
            raise InputError(f"limit must be 1…{MAX_PAGE}, got {query.limit}")
        equal = (
            (Run.serial, query.serial),
            (Run.station_id, query.station_id),
            (Run.lot, query.lot),
            (Run.part_number, query.part_number),
            (Run.verdict, query.verdict),
        )
        stmt = select(Run).where(*(column == value for column, value in equal if value is not None))
        if query.since is not None:
            stmt = stmt.where(Run.started_at >= query.since)
        if query.until is not None:
            stmt = stmt.where(Run.started_at < query.until)
        if query.cursor is not None:
            stmt = stmt.where(tuple_(Run.started_at, Run.id) < tuple_(*decode_cursor(query.cursor)))
        stmt = stmt.order_by(Run.started_at.desc(), Run.id.desc()).limit(query.limit + 1)
        runs = self.session.scalars(stmt).all()
        page, more = runs[: query.limit], len(runs) > query.limit
        cursor = encode_cursor(page[-1].started_at, page[-1].id) if more else None
        return RunPage(runs=self._summaries(page), next_cursor=cursor)

    def refresh_units(self) -> int:
        """Write every unit's answer from ``runs``; return the number of units.

        A bulk load of runs uses it; answers missing or of an older shape
        (:class:`station.domain.record.unit_state.UnitCalibration`) are written with it when the
        database is upgraded (:mod:`db.database`).
        """
        return refresh_answers(self.session)

    def _latest(self, *where: ColumnElement[bool]) -> RunSummary | None:
        """The latest run (by start time) of those ``where`` selects."""
        run = self.session.scalars(
            select(Run).where(*where).order_by(Run.started_at.desc(), Run.id.desc()).limit(1)
        ).one_or_none()
        return None if run is None else self._summaries([run])[0]

    def _summaries(self, runs: Sequence[Run]) -> list[RunSummary]:
        failed = [run.id for run in runs if run.verdict == "fail"]
        failures = failures_of(self.session, failed)
        return [summary_of(run, failures[run.id]) for run in runs]

    # -- API keys ----------------------------------------------------------------------

    def create_key(self, holder: str, scope: KeyScope = "station") -> str:
        """A new API key of station (or lab) ``holder``; only its hash is stored, so show it now."""
        key = "csk_" + secrets.token_urlsafe(32)
        self.session.add(
            StationKey(
                station_id=holder,
                scope=scope,
                key_sha256=key_sha256(key),
                created_at=datetime.now(UTC),
            )
        )
        return key

    def revoke_keys(self, holder: str, scope: KeyScope = "station") -> int:
        """Revoke every valid key of station (or lab) ``holder``; return how many there were."""
        revoked = self.session.scalars(
            update(StationKey)
            .where(
                StationKey.station_id == holder,
                StationKey.scope == scope,
                StationKey.revoked_at.is_(None),
            )
            .values(revoked_at=datetime.now(UTC))
            .returning(StationKey.id)
        ).all()
        return len(revoked)

    def key_holder(self, key: str) -> KeyHolder | None:
        """Who a valid (not revoked) key belongs to, and what it may store."""
        row = self.session.execute(
            select(StationKey.station_id, StationKey.scope).where(
                StationKey.key_sha256 == key_sha256(key), StationKey.revoked_at.is_(None)
            )
        ).one_or_none()
        # The table's check constraint holds the scope to the two names.
        return None if row is None else KeyHolder(row.station_id, cast(KeyScope, row.scope))

    # -- reviews of units on hold ---------------------------------------------------------

    def add_review(self, review: HoldReview) -> None:
        """Store a review of a unit on hold: ``review.run_id`` must be the unit's latest
        run, and that run failed; :class:`ReviewRefusedError` otherwise (None stored)."""
        latest = self.latest_for_serial(review.serial)
        if latest is None:
            raise ReviewRefusedError(f"no calibration run of serial {review.serial}")
        if latest.run_id != review.run_id:
            raise ReviewRefusedError(
                f"run {review.run_id} is not the latest run of {review.serial} "
                f"(run {latest.run_id} is): review the unit's latest run"
            )
        if latest.verdict != "fail":
            raise ReviewRefusedError(
                f"{review.serial} is not on hold: its latest run {latest.run_id} passed"
            )
        self.session.add(ReviewRow(**review.model_dump()))
        self.session.flush()

    def reviews(self, serial: str) -> list[HoldReview]:
        """Every review of the unit, oldest first."""
        rows = self.session.scalars(
            select(ReviewRow)
            .where(ReviewRow.serial == serial)
            .order_by(ReviewRow.reviewed_at, ReviewRow.id)
        ).all()
        return [HoldReview.model_validate(row, from_attributes=True) for row in rows]

    # -- gyro error-model fits ----------------------------------------------------------

    def add_gyro_fit(self, fit: GyroFitRecord) -> None:
        """Store a unit's gyro fit; the latest one is the unit's current."""
        self.session.add(
            GyroFit(
                serial=fit.serial,
                fitted_at=fit.fitted_at,
                source=fit.source,
                document=fit.model_dump(mode="json", include={"report", "dwells"}),
            )
        )
        self.session.flush()

    def latest_gyro_fit(self, serial: str) -> GyroFitRecord | None:
        """The unit's latest gyro fit, or None."""
        row = self.session.scalars(
            select(GyroFit)
            .where(GyroFit.serial == serial)
            .order_by(GyroFit.fitted_at.desc(), GyroFit.id.desc())
            .limit(1)
        ).one_or_none()
        if row is None:
            return None
        fields = {name: getattr(row, name) for name in ("serial", "fitted_at", "source")}
        return GyroFitRecord.model_validate({**fields, **row.document})


class ReviewRefusedError(CalstationError):
    """A review of a unit that is not on hold, or of a run that is not its latest."""
