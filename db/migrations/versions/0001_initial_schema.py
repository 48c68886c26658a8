"""Initial schema: runs, their poses and failure reasons, station API keys.

Revision ID: 0001
Revises:
Create Date: 2026-11-22 10:21:24.190610
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op
from sqlalchemy.dialects import postgresql

revision: str = "0001"
down_revision: str | None = None
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: The DDL type of :class:`db.base.UtcDateTime`, written out: a migration imports no project
#: code, so editing db/ never changes what this revision creates.
UtcDateTime = sa.DateTime(timezone=True)


def upgrade() -> None:
    op.create_table(
        "runs",
        sa.Column(
            "id",
            sa.BigInteger().with_variant(sa.Integer(), "sqlite"),
            autoincrement=True,
            nullable=False,
        ),
        sa.Column("run_id", sa.Uuid(), nullable=False),
        sa.Column("serial", sa.String(length=64), nullable=False),
        sa.Column("station_id", sa.String(length=64), nullable=False),
        sa.Column("operator_id", sa.String(length=64), nullable=False),
        sa.Column("started_at", UtcDateTime, nullable=False),
        sa.Column("finished_at", UtcDateTime, nullable=False),
        sa.Column("received_at", UtcDateTime, nullable=False),
        sa.Column("software_version", sa.String(length=64), nullable=False),
        sa.Column("algorithm", sa.String(length=64), nullable=False),
        sa.Column("model", sa.String(length=4), nullable=False),
        sa.Column("limits_name", sa.String(length=64), nullable=False),
        sa.Column("limits_version", sa.String(length=64), nullable=False),
        sa.Column("limits_sha256", sa.String(length=64), nullable=False),
        sa.Column("verdict", sa.String(length=4), nullable=False),
        sa.Column("offset_x", sa.Double(), nullable=True),
        sa.Column("offset_y", sa.Double(), nullable=True),
        sa.Column("offset_z", sa.Double(), nullable=True),
        sa.Column("sensitivity_x", sa.Double(), nullable=True),
        sa.Column("sensitivity_y", sa.Double(), nullable=True),
        sa.Column("sensitivity_z", sa.Double(), nullable=True),
        sa.Column(
            "matrix",
            sa.JSON().with_variant(postgresql.JSONB(astext_type=sa.Text()), "postgresql"),
            nullable=True,
        ),
        sa.Column("residual_rms_mg", sa.Double(), nullable=True),
        sa.Column("residual_max_mg", sa.Double(), nullable=True),
        sa.Column("condition_number", sa.Double(), nullable=True),
        sa.Column("verification_error_mg", sa.Double(), nullable=True),
        sa.Column(
            "gyro",
            sa.JSON().with_variant(postgresql.JSONB(astext_type=sa.Text()), "postgresql"),
            nullable=True,
        ),
        sa.Column("record_sha256", sa.String(length=64), nullable=False),
        sa.CheckConstraint("model IN ('six', 'nine')", name=op.f("ck_runs_model")),
        sa.CheckConstraint("verdict IN ('pass', 'fail')", name=op.f("ck_runs_verdict")),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_runs")),
        sa.UniqueConstraint("run_id", name=op.f("uq_runs_run_id")),
    )
    with op.batch_alter_table("runs", schema=None) as batch_op:
        batch_op.create_index(
            "ix_runs_serial_started_at", ["serial", "started_at", "id"], unique=False
        )
        batch_op.create_index("ix_runs_started_at", ["started_at", "id"], unique=False)
        batch_op.create_index(
            "ix_runs_station_id_started_at", ["station_id", "started_at", "id"], unique=False
        )
        batch_op.create_index(
            "ix_runs_verdict_started_at", ["verdict", "started_at", "id"], unique=False
        )

    op.create_table(
        "station_keys",
        sa.Column(
            "id",
            sa.BigInteger().with_variant(sa.Integer(), "sqlite"),
            autoincrement=True,
            nullable=False,
        ),
        sa.Column("station_id", sa.String(length=64), nullable=False),
        sa.Column("key_sha256", sa.String(length=64), nullable=False),
        sa.Column("created_at", UtcDateTime, nullable=False),
        sa.Column("revoked_at", UtcDateTime, nullable=True),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_station_keys")),
        sa.UniqueConstraint("key_sha256", name=op.f("uq_station_keys_key_sha256")),
    )
    with op.batch_alter_table("station_keys", schema=None) as batch_op:
        batch_op.create_index(
            batch_op.f("ix_station_keys_station_id"), ["station_id"], unique=False
        )

    op.create_table(
        "poses",
        sa.Column(
            "id",
            sa.BigInteger().with_variant(sa.Integer(), "sqlite"),
            autoincrement=True,
            nullable=False,
        ),
        sa.Column("run_pk", sa.BigInteger().with_variant(sa.Integer(), "sqlite"), nullable=False),
        sa.Column("index", sa.Integer(), nullable=False),
        sa.Column("name", sa.String(length=64), nullable=False),
        sa.Column("role", sa.String(length=8), nullable=False),
        sa.Column("mean_x", sa.Double(), nullable=False),
        sa.Column("mean_y", sa.Double(), nullable=False),
        sa.Column("mean_z", sa.Double(), nullable=False),
        sa.Column("std_x", sa.Double(), nullable=False),
        sa.Column("std_y", sa.Double(), nullable=False),
        sa.Column("std_z", sa.Double(), nullable=False),
        sa.Column("sample_count", sa.Integer(), nullable=False),
        sa.Column("gyro_x", sa.Double(), nullable=True),
        sa.Column("gyro_y", sa.Double(), nullable=True),
        sa.Column("gyro_z", sa.Double(), nullable=True),
        sa.Column("temperature_c", sa.Double(), nullable=True),
        sa.Column("crc_errors", sa.Integer(), nullable=False),
        sa.Column("gaps", sa.Integer(), nullable=False),
        sa.Column("resyncs", sa.Integer(), nullable=False),
        sa.Column("lost_samples", sa.Integer(), nullable=False),
        sa.Column(
            "replaced",
            sa.JSON().with_variant(postgresql.JSONB(astext_type=sa.Text()), "postgresql"),
            nullable=False,
        ),
        sa.CheckConstraint("role IN ('fit', 'verify')", name=op.f("ck_poses_role")),
        sa.ForeignKeyConstraint(
            ["run_pk"], ["runs.id"], name=op.f("fk_poses_run_pk_runs"), ondelete="CASCADE"
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_poses")),
        sa.UniqueConstraint("run_pk", "index", name=op.f("uq_poses_run_pk_index")),
    )
    op.create_table(
        "run_failures",
        sa.Column(
            "id",
            sa.BigInteger().with_variant(sa.Integer(), "sqlite"),
            autoincrement=True,
            nullable=False,
        ),
        sa.Column("run_pk", sa.BigInteger().with_variant(sa.Integer(), "sqlite"), nullable=False),
        sa.Column("position", sa.Integer(), nullable=False),
        sa.Column("code", sa.String(length=64), nullable=False),
        sa.Column("message", sa.String(length=500), nullable=False),
        sa.Column("measured", sa.Double(), nullable=True),
        sa.Column("lower", sa.Double(), nullable=True),
        sa.Column("upper", sa.Double(), nullable=True),
        sa.Column("axis", sa.String(length=1), nullable=True),
        sa.Column("pose", sa.Integer(), nullable=True),
        sa.ForeignKeyConstraint(
            ["run_pk"], ["runs.id"], name=op.f("fk_run_failures_run_pk_runs"), ondelete="CASCADE"
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_run_failures")),
        sa.UniqueConstraint("run_pk", "position", name=op.f("uq_run_failures_run_pk_position")),
    )
    with op.batch_alter_table("run_failures", schema=None) as batch_op:
        batch_op.create_index("ix_run_failures_code", ["code"], unique=False)


def downgrade() -> None:
    with op.batch_alter_table("run_failures", schema=None) as batch_op:
        batch_op.drop_index("ix_run_failures_code")

    op.drop_table("run_failures")
    op.drop_table("poses")
    with op.batch_alter_table("station_keys", schema=None) as batch_op:
        batch_op.drop_index(batch_op.f("ix_station_keys_station_id"))

    op.drop_table("station_keys")
    with op.batch_alter_table("runs", schema=None) as batch_op:
        batch_op.drop_index("ix_runs_verdict_started_at")
        batch_op.drop_index("ix_runs_station_id_started_at")
        batch_op.drop_index("ix_runs_started_at")
        batch_op.drop_index("ix_runs_serial_started_at")

    op.drop_table("runs")
