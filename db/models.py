"""Tables of the results database.

``runs`` is append-only: a retest is a new row, a unit's current verdict is its latest
run's (by ``started_at``), its first run stays for first-pass yield. ``run_ids`` registers
each run (its UUID, its key, its start) and every row that belongs to a run refers to it
there, so that ``runs`` and ``poses`` can be partitioned by year on PostgreSQL (migration
0025, :mod:`db.partitions`). Each run owns its ``poses`` and its ``run_failures``;
``units`` holds each unit's current calibration, ready to serve, kept in step with
``runs`` at every submission; ``station_keys`` holds the hashed API keys of the stations
that submit over HTTP.

``run_facts`` and the ``report_*`` tables hold what the end-of-line report derives from
those rows (per-run facts, daily roll-ups); :mod:`db.rollups` builds and maintains them.
"""

import uuid
from datetime import datetime
from typing import Any

from sqlalchemy import (
    BigInteger,
    Boolean,
    CheckConstraint,
    Double,
    ForeignKey,
    Index,
    Integer,
    String,
    Text,
    UniqueConstraint,
    Uuid,
    text,
)
from sqlalchemy.orm import Mapped, mapped_column

from db.base import Base, JsonDocument, UtcDateTime
from station.domain.quality.capability import HISTOGRAM_BINS

#: Primary keys: BIGINT on PostgreSQL; SQLite's rowid alias must be spelled INTEGER.
BigId = BigInteger().with_variant(Integer(), "sqlite")

NAME = 64


class RunId(Base):
    """The register of runs: each run's UUID, unique, and the key its rows share.

    ``run_pk`` numbers the runs (``runs.id`` is the same number); the unique ``run_id``
    decides whether a submission is new (``INSERT … ON CONFLICT (run_id) DO NOTHING``).
    The register is not partitioned, so ``runs`` needs no unique constraint of its own:
    PostgreSQL requires each unique constraint of a partitioned table to hold its
    partition key, which would let a UUID reused with another start through.
    """

    __tablename__ = "run_ids"

    run_pk: Mapped[int] = mapped_column(BigId, primary_key=True, autoincrement=True)
    run_id: Mapped[uuid.UUID] = mapped_column(Uuid(), unique=True)
    started_at: Mapped[datetime] = mapped_column(UtcDateTime())


#: How a run's rows refer to it: by its key in the register.
RUN_KEY = "run_ids.run_pk"


class Run(Base):
    """One calibration attempt of one unit at one station.

    On PostgreSQL the table is partitioned by year of ``started_at`` and its primary key
    is ``(id, started_at)`` (migration 0025); the models state the key both backends share.
    """

    __tablename__ = "runs"
    __table_args__ = (
        CheckConstraint("verdict IN ('pass', 'fail')", name="verdict"),
        CheckConstraint("model IN ('six', 'nine')", name="model"),
        CheckConstraint("disposition IN ('ship', 'retest', 'rework')", name="disposition"),
        CheckConstraint("purpose IN ('golden')", name="purpose"),
        CheckConstraint("decision_rule IN ('simple', 'guarded')", name="decision_rule"),
        Index("ix_runs_serial_started_at", "serial", "started_at", "id"),
        Index("ix_runs_station_id_started_at", "station_id", "started_at", "id"),
        Index("ix_runs_verdict_started_at", "verdict", "started_at", "id"),
        Index("ix_runs_started_at", "started_at", "id"),
        Index("ix_runs_lot_started_at", "lot", "started_at", "id"),
        Index("ix_runs_part_number_started_at", "part_number", "started_at", "id"),
    )

    id: Mapped[int] = mapped_column(
        BigId, ForeignKey(RUN_KEY, ondelete="CASCADE"), primary_key=True, autoincrement=False
    )
    run_id: Mapped[uuid.UUID] = mapped_column(Uuid())
    serial: Mapped[str] = mapped_column(String(NAME))
    station_id: Mapped[str] = mapped_column(String(NAME))
    operator_id: Mapped[str] = mapped_column(String(NAME))
    #: The unit's production lot, when the station knows it.
    lot: Mapped[str | None] = mapped_column(String(NAME))
    #: The unit's product (runs from before products: DIXX-A12, migration 0014).
    part_number: Mapped[str] = mapped_column(String(NAME))
    #: The fixture's slot (1 on a one-port station); None on runs stored before 0015.
    fixture_slot: Mapped[int | None] = mapped_column(Integer())
    started_at: Mapped[datetime] = mapped_column(UtcDateTime())
    finished_at: Mapped[datetime] = mapped_column(UtcDateTime())
    received_at: Mapped[datetime] = mapped_column(UtcDateTime())
    software_version: Mapped[str] = mapped_column(String(NAME))
    algorithm: Mapped[str] = mapped_column(String(NAME))
    model: Mapped[str] = mapped_column(String(4))
    limits_name: Mapped[str] = mapped_column(String(NAME))
    limits_version: Mapped[str] = mapped_column(String(NAME))
    limits_sha256: Mapped[str] = mapped_column(String(64))
    verdict: Mapped[str] = mapped_column(String(4))
    #: Where the station sent the unit (ship, retest, rework); older runs have none.
    disposition: Mapped[str | None] = mapped_column(String(8))
    #: ``golden``: the station's golden-unit check, not a production unit (null: production).
    purpose: Mapped[str | None] = mapped_column(String(8))
    offset_x: Mapped[float | None] = mapped_column(Double())
    offset_y: Mapped[float | None] = mapped_column(Double())
    offset_z: Mapped[float | None] = mapped_column(Double())
    sensitivity_x: Mapped[float | None] = mapped_column(Double())
    sensitivity_y: Mapped[float | None] = mapped_column(Double())
    sensitivity_z: Mapped[float | None] = mapped_column(Double())
    matrix: Mapped[list[list[float]] | None] = mapped_column(JsonDocument)
    residual_rms_mg: Mapped[float | None] = mapped_column(Double())
    residual_max_mg: Mapped[float | None] = mapped_column(Double())
    condition_number: Mapped[float | None] = mapped_column(Double())
    verification_error_mg: Mapped[float | None] = mapped_column(Double())
    #: The fit poses (0-based) the solve left out as inconsistent; None: none was.
    excluded_poses: Mapped[list[int] | None] = mapped_column(JsonDocument)
    gyro: Mapped[dict[str, Any] | None] = mapped_column(JsonDocument)
    #: The gyro matrix K fitted from the moves (whole-unit runs), as
    #: :class:`station.domain.record.records.GyroMatrixRecord`'s JSON; None otherwise.
    gyro_matrix: Mapped[dict[str, Any] | None] = mapped_column(JsonDocument)
    #: Expanded uncertainties of the coefficients, as
    #: :class:`station.domain.record.records.UncertaintyRecord`'s JSON; None on older runs.
    uncertainty: Mapped[dict[str, Any] | None] = mapped_column(JsonDocument)
    #: The decision rule that judged the run; None on older runs (simple acceptance).
    decision_rule: Mapped[str | None] = mapped_column(String(8))
    #: The decision rule that judged each limit, by check code; None on older runs
    #: (0024: their rule guarded the offsets, sensitivities and gyro biases only).
    check_rules: Mapped[dict[str, str] | None] = mapped_column(JsonDocument)
    #: The coefficients the unit held before the run wrote its own, as
    #: :class:`station.domain.record.records.AsFound`'s JSON; None on older runs (0022).
    as_found: Mapped[dict[str, Any] | None] = mapped_column(JsonDocument)
    #: SHA-256 of the submitted record's canonical JSON: tells a retry from a clash.
    record_sha256: Mapped[str] = mapped_column(String(64))


class RunPose(Base):
    """One still pose of a run: the accepted capture (counts, deg/s, °C) and link health.

    ``started_at`` is the run's: on PostgreSQL the table is partitioned by its year, as
    ``runs`` is, and its keys hold it (migration 0025).
    """

    __tablename__ = "poses"
    __table_args__ = (
        UniqueConstraint("run_pk", "index", "started_at"),
        CheckConstraint("role IN ('fit', 'verify')", name="role"),
    )

    id: Mapped[int] = mapped_column(BigId, primary_key=True, autoincrement=True)
    run_pk: Mapped[int] = mapped_column(ForeignKey(RUN_KEY, ondelete="CASCADE"))
    started_at: Mapped[datetime] = mapped_column(UtcDateTime())
    index: Mapped[int] = mapped_column(Integer())
    name: Mapped[str] = mapped_column(String(NAME))
    role: Mapped[str] = mapped_column(String(8))
    mean_x: Mapped[float] = mapped_column(Double())
    mean_y: Mapped[float] = mapped_column(Double())
    mean_z: Mapped[float] = mapped_column(Double())
    std_x: Mapped[float] = mapped_column(Double())
    std_y: Mapped[float] = mapped_column(Double())
    std_z: Mapped[float] = mapped_column(Double())
    sample_count: Mapped[int] = mapped_column(Integer())
    gyro_x: Mapped[float | None] = mapped_column(Double())
    gyro_y: Mapped[float | None] = mapped_column(Double())
    gyro_z: Mapped[float | None] = mapped_column(Double())
    temperature_c: Mapped[float | None] = mapped_column(Double())
    crc_errors: Mapped[int] = mapped_column(Integer())
    gaps: Mapped[int] = mapped_column(Integer())
    resyncs: Mapped[int] = mapped_column(Integer())
    lost_samples: Mapped[int] = mapped_column(Integer())
    #: Captures of this pose thrown away and taken again, for audit.
    replaced: Mapped[list[dict[str, Any]]] = mapped_column(JsonDocument)


class RunFailure(Base):
    """One reason a run failed: the check, the measured value and its bounds."""

    __tablename__ = "run_failures"
    __table_args__ = (
        UniqueConstraint("run_pk", "position"),
        Index("ix_run_failures_code", "code"),
    )

    id: Mapped[int] = mapped_column(BigId, primary_key=True, autoincrement=True)
    run_pk: Mapped[int] = mapped_column(ForeignKey(RUN_KEY, ondelete="CASCADE"))
    position: Mapped[int] = mapped_column(Integer())
    code: Mapped[str] = mapped_column(String(NAME))
    message: Mapped[str] = mapped_column(String(500))
    measured: Mapped[float | None] = mapped_column(Double())
    lower: Mapped[float | None] = mapped_column(Double())
    upper: Mapped[float | None] = mapped_column(Double())
    axis: Mapped[str | None] = mapped_column(String(1))
    pose: Mapped[int | None] = mapped_column(Integer())
    #: The value's expanded uncertainty U when guarded acceptance refused it (0016).
    uncertainty: Mapped[float | None] = mapped_column(Double())


class Unit(Base):
    """A unit's current state: which run is its latest, and that run's answer, serialised.

    ``calibration`` is the JSON of :class:`station.domain.record.unit_state.UnitCalibration`
    for the run ``run_pk``, which is the unit's latest by ``(started_at, id)`` — the order
    ``ix_runs_serial_started_at`` walks. It is written in the transaction that stores the
    run (:mod:`db.store.units`), so a unit lookup reads one row by primary key. Answers
    missing or of an older shape are written at upgrade (:mod:`db.database`).
    """

    __tablename__ = "units"

    serial: Mapped[str] = mapped_column(String(NAME), primary_key=True)
    run_pk: Mapped[int] = mapped_column(ForeignKey(RUN_KEY, ondelete="CASCADE"))
    started_at: Mapped[datetime] = mapped_column(UtcDateTime())
    calibration: Mapped[str] = mapped_column(Text())


class GyroFit(Base):
    """A fit of the gyro error model to a unit's rate-table / centrifuge log.

    ``document`` holds the whole :class:`station.domain.gyro.fit.GyroFitReport` (the JSON of
    ``calstation gyro fit --json``) and the log's dwells; a unit's current fit is its
    latest.
    """

    __tablename__ = "gyro_fits"
    __table_args__ = (Index("ix_gyro_fits_serial_fitted_at", "serial", "fitted_at", "id"),)

    id: Mapped[int] = mapped_column(BigId, primary_key=True, autoincrement=True)
    serial: Mapped[str] = mapped_column(String(NAME))
    fitted_at: Mapped[datetime] = mapped_column(UtcDateTime())
    source: Mapped[str] = mapped_column(String(255))
    #: ``{"report": …, "dwells": …}``: the fit and the log's dwells it came from.
    document: Mapped[dict[str, Any]] = mapped_column(JsonDocument)


class HoldReview(Base):
    """A quality review of a unit on hold (:class:`station.domain.record.records.HoldReview`),
    append-only: a unit's latest review decides whether it may be calibrated again."""

    __tablename__ = "hold_reviews"
    __table_args__ = (
        CheckConstraint("decision IN ('retest', 'scrap')", name="decision"),
        Index("ix_hold_reviews_serial_reviewed_at", "serial", "reviewed_at", "id"),
    )

    id: Mapped[int] = mapped_column(BigId, primary_key=True, autoincrement=True)
    serial: Mapped[str] = mapped_column(String(NAME))
    run_id: Mapped[uuid.UUID] = mapped_column(Uuid())
    reviewed_at: Mapped[datetime] = mapped_column(UtcDateTime())
    reviewer: Mapped[str] = mapped_column(String(NAME))
    root_cause: Mapped[str] = mapped_column(Text())
    repair_action: Mapped[str] = mapped_column(Text())
    decision: Mapped[str] = mapped_column(String(8))


class StationKey(Base):
    """An API key, stored as its SHA-256 (the key itself is shown once).

    ``scope`` says what it may store: ``station``, the runs of station ``station_id``;
    ``lab``, units' gyro fits; ``quality``, reviews of units on hold (``station_id``
    then names the lab or the quality engineer).
    """

    __tablename__ = "station_keys"
    __table_args__ = (CheckConstraint("scope IN ('station', 'lab', 'quality')", name="scope"),)

    id: Mapped[int] = mapped_column(BigId, primary_key=True, autoincrement=True)
    station_id: Mapped[str] = mapped_column(String(NAME), index=True)
    scope: Mapped[str] = mapped_column(String(8), server_default="station")
    key_sha256: Mapped[str] = mapped_column(String(64), unique=True)
    created_at: Mapped[datetime] = mapped_column(UtcDateTime())
    revoked_at: Mapped[datetime | None] = mapped_column(UtcDateTime())


class Signatory(Base):
    """An authorised signatory of certificates and the public half of their Ed25519 key
    (hex; the private half stays in the file they keep, :mod:`station.domain.record.signature`)."""

    __tablename__ = "signatories"

    id: Mapped[int] = mapped_column(BigId, primary_key=True, autoincrement=True)
    name: Mapped[str] = mapped_column(String(NAME), unique=True)
    public_key: Mapped[str] = mapped_column(String(64))
    created_at: Mapped[datetime] = mapped_column(UtcDateTime())


class CertificateSignature(Base):
    """A signatory's signature of a run's certificate
    (:class:`station.domain.record.signature.Signature`): one per run."""

    __tablename__ = "certificate_signatures"

    id: Mapped[int] = mapped_column(BigId, primary_key=True, autoincrement=True)
    run_id: Mapped[uuid.UUID] = mapped_column(Uuid(), unique=True)
    certificate: Mapped[str] = mapped_column(String(NAME))
    record_sha256: Mapped[str] = mapped_column(String(64))
    signatory: Mapped[str] = mapped_column(String(NAME))
    signed_at: Mapped[datetime] = mapped_column(UtcDateTime())
    signature: Mapped[str] = mapped_column(String(128))


class RunFacts(Base):
    """What the report derives from one run and the runs around it (:mod:`db.rollups`).

    Order is ``(started_at, id)``. ``attempt``: the run is an attempt (not an operator's
    abort, :mod:`db.rollups`); ``line_first``: it is the unit's first attempt (no earlier
    attempt of the unit); ``line_latest``: its latest (no later one); ``noise_*``: the
    run's pose noise summed over its poses; ``line_final_pass``: ``line_first`` and the
    unit's latest attempt passed; ``unit_runs``: how many runs the unit has, aborts
    included. ``chart_previous``, for a run with coefficients: the latest earlier run of
    the line with coefficients (the other end of this run's moving range).
    """

    __tablename__ = "run_facts"

    run_pk: Mapped[int] = mapped_column(
        ForeignKey(RUN_KEY, ondelete="CASCADE"), primary_key=True, autoincrement=False
    )
    first_failure: Mapped[str | None] = mapped_column(String(NAME))
    poses: Mapped[int] = mapped_column(Integer())
    gyro_bias_x: Mapped[float | None] = mapped_column(Double())
    gyro_bias_y: Mapped[float | None] = mapped_column(Double())
    gyro_bias_z: Mapped[float | None] = mapped_column(Double())
    #: Σ std and Σ std² over the run's poses, per axis (None: no poses).
    noise_sum_x: Mapped[float | None] = mapped_column(Double())
    noise_sum_y: Mapped[float | None] = mapped_column(Double())
    noise_sum_z: Mapped[float | None] = mapped_column(Double())
    noise_squares_x: Mapped[float | None] = mapped_column(Double())
    noise_squares_y: Mapped[float | None] = mapped_column(Double())
    noise_squares_z: Mapped[float | None] = mapped_column(Double())
    attempt: Mapped[bool] = mapped_column(Boolean())
    line_first: Mapped[bool] = mapped_column(Boolean())
    line_latest: Mapped[bool] = mapped_column(Boolean())
    line_final_pass: Mapped[bool] = mapped_column(Boolean())
    unit_runs: Mapped[int] = mapped_column(Integer())
    chart_previous: Mapped[int | None] = mapped_column(BigId)


class _Bucket:
    """The key of a roll-up row: a UTC day (days since 1970-01-01), station, operator, lot
    and product (part number), so that a product's rows read the roll-ups as a station's do.

    A run without a lot is counted under the lot ``''``.
    """

    day: Mapped[int] = mapped_column(Integer(), primary_key=True)
    station_id: Mapped[str] = mapped_column(String(NAME), primary_key=True)
    operator_id: Mapped[str] = mapped_column(String(NAME), primary_key=True)
    lot: Mapped[str] = mapped_column(String(NAME), primary_key=True)
    part_number: Mapped[str] = mapped_column(String(NAME), primary_key=True)


class ReportCounts(_Bucket, Base):
    """Per bucket and limits profile: the runs' counts, times and unit flags (sums).

    ``line_units``: units whose first attempt is in the bucket, ``line_first_pass`` /
    ``line_final_pass``: of those, the units whose first / latest attempt passed;
    ``retests``: attempts that are not their unit's first; ``aborts``: operator aborts
    (runs, never attempts)."""

    __tablename__ = "report_counts"

    limits_name: Mapped[str] = mapped_column(String(NAME), primary_key=True)
    limits_version: Mapped[str] = mapped_column(String(NAME), primary_key=True)
    limits_sha256: Mapped[str] = mapped_column(String(64), primary_key=True)
    runs: Mapped[int] = mapped_column(Integer())
    runs_passed: Mapped[int] = mapped_column(Integer())
    duration_ms: Mapped[int] = mapped_column(BigInteger())
    poses: Mapped[int] = mapped_column(Integer())
    first_start: Mapped[datetime] = mapped_column(UtcDateTime())
    last_finish: Mapped[datetime] = mapped_column(UtcDateTime())
    line_units: Mapped[int] = mapped_column(Integer())
    line_first_pass: Mapped[int] = mapped_column(Integer())
    line_final_pass: Mapped[int] = mapped_column(Integer())
    retests: Mapped[int] = mapped_column(Integer())
    aborts: Mapped[int] = mapped_column(Integer())
    charted: Mapped[int] = mapped_column(Integer())
    mr_offset_x: Mapped[float] = mapped_column(Double())
    mr_offset_y: Mapped[float] = mapped_column(Double())
    mr_offset_z: Mapped[float] = mapped_column(Double())
    mr_sensitivity_x: Mapped[float] = mapped_column(Double())
    mr_sensitivity_y: Mapped[float] = mapped_column(Double())
    mr_sensitivity_z: Mapped[float] = mapped_column(Double())


class ReportFailures(_Bucket, Base):
    """Per bucket and first failure reason: failing runs."""

    __tablename__ = "report_failures"

    code: Mapped[str] = mapped_column(String(NAME), primary_key=True)
    runs: Mapped[int] = mapped_column(Integer())


class ReportParameters(_Bucket, Base):
    """Per bucket and parameter: n, Σ(x − c), Σ(x − c)², min, max, out of limits, marginal
    and the 30 histogram bins ``h00…h29``, with bins and c from ``report_bounds``."""

    __tablename__ = "report_parameters"

    parameter: Mapped[str] = mapped_column(String(NAME), primary_key=True)
    n: Mapped[int] = mapped_column(Integer())
    sum: Mapped[float] = mapped_column(Double())
    squares: Mapped[float] = mapped_column(Double())
    min: Mapped[float] = mapped_column(Double())
    max: Mapped[float] = mapped_column(Double())
    outside: Mapped[int] = mapped_column(Integer())
    marginal: Mapped[int] = mapped_column(Integer())


for _bin in range(HISTOGRAM_BINS):
    setattr(
        ReportParameters, f"h{_bin:02d}", mapped_column(f"h{_bin:02d}", Integer(), nullable=False)
    )


class StoredLimitsProfile(Base):
    """A limits profile as a run submitted it: its canonical JSON, keyed by its SHA-256.

    Stored the first time a run carries it (:mod:`db.store.limits_profiles`), never changed:
    ``document`` hashes to ``sha256``. ``runs.limits_sha256`` refers to it; no foreign
    key, because runs from stations older than stored profiles refer to profiles whose
    content the server never received (and SQLite could add the key only by copying
    ``runs``).
    """

    __tablename__ = "limits_profiles"

    sha256: Mapped[str] = mapped_column(String(64), primary_key=True)
    name: Mapped[str] = mapped_column(String(NAME))
    version: Mapped[str] = mapped_column(String(NAME))
    document: Mapped[str] = mapped_column(Text())


class ReportBounds(Base):
    """The limits (per limits family) the ``report_parameters`` bins were counted with."""

    __tablename__ = "report_bounds"

    family: Mapped[str] = mapped_column(String(NAME), primary_key=True)
    lower: Mapped[float | None] = mapped_column(Double())
    upper: Mapped[float | None] = mapped_column(Double())


class StoredAlert(Base):
    """An alert that fired (:mod:`station.domain.quality.alerts`, :mod:`db.report.alerts`).

    ``event_key`` is unique: an event is stored once, however many server processes see
    it. ``watch`` names the rule (its kind, scope and thresholds); at most one alert of a
    rule is open (``cleared_at`` NULL), a partial unique index. ``delivered_at``: when the
    webhook took it; ``next_attempt_at``: not posted again before it (a process posting
    it holds it until then, a refused post is tried again then)."""

    __tablename__ = "alerts"
    __table_args__ = (
        Index(
            "ux_alerts_open_watch",
            "watch",
            unique=True,
            sqlite_where=text("cleared_at IS NULL"),
            postgresql_where=text("cleared_at IS NULL"),
        ),
        Index("ix_alerts_fired_at", "fired_at", "id"),
    )

    id: Mapped[int] = mapped_column(BigId, primary_key=True, autoincrement=True)
    event_key: Mapped[str] = mapped_column(String(255), unique=True)
    watch: Mapped[str] = mapped_column(String(255))
    rule: Mapped[str] = mapped_column(String(16))
    scope: Mapped[str] = mapped_column(String(NAME))
    message: Mapped[str] = mapped_column(Text())
    evidence: Mapped[dict[str, Any]] = mapped_column(JsonDocument)
    fired_at: Mapped[datetime] = mapped_column(UtcDateTime())
    cleared_at: Mapped[datetime | None] = mapped_column(UtcDateTime())
    delivered_at: Mapped[datetime | None] = mapped_column(UtcDateTime())
    attempts: Mapped[int] = mapped_column(Integer())
    next_attempt_at: Mapped[datetime] = mapped_column(UtcDateTime())


class StationOutbox(Base):
    """A station's outbox as it last reported it with a run it sent
    (:mod:`station.domain.record.outbox_report`): one row per station, the latest report."""

    __tablename__ = "station_outboxes"

    station_id: Mapped[str] = mapped_column(String(NAME), primary_key=True)
    queued: Mapped[int] = mapped_column(Integer())
    oldest_s: Mapped[int] = mapped_column(Integer())
    set_aside: Mapped[int] = mapped_column(Integer())
    reported_at: Mapped[datetime] = mapped_column(UtcDateTime())
