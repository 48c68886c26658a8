"""A lot per run; the end-of-line report's per-run facts and daily roll-ups.

Revision ID: 0003
Revises: 0002

Adds ``runs.lot`` (and ``ix_runs_lot_started_at``) and the tables of :mod:`db.rollups`.
The schema only: the roll-ups of the runs already stored are derived data, filled once
the database reaches the head (:func:`db.database.rewrite_if_stale`), by the code of that
day, so this revision means the same thing forever.
"""

from collections.abc import Sequence
from typing import Any

import sqlalchemy as sa
from alembic import op

revision: str = "0003"
down_revision: str | None = "0002"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

BigId = sa.BigInteger().with_variant(sa.Integer(), "sqlite")


def _bucket() -> list[sa.Column[object]]:
    return [
        sa.Column("day", sa.Integer(), nullable=False),
        sa.Column("station_id", sa.String(length=64), nullable=False),
        sa.Column("operator_id", sa.String(length=64), nullable=False),
        sa.Column("lot", sa.String(length=64), nullable=False),
    ]


#: The value columns of ``report_counts`` at this revision and their types, written out
#: (not taken from :mod:`db.rollups`): editing db/ never changes what this revision creates.
COUNT_COLUMNS: tuple[tuple[str, sa.types.TypeEngine[Any]], ...] = (
    ("runs", sa.Integer()),
    ("runs_passed", sa.Integer()),
    ("duration_ms", sa.BigInteger()),
    ("poses", sa.Integer()),
    ("first_start", sa.DateTime(timezone=True)),
    ("last_finish", sa.DateTime(timezone=True)),
    ("line_units", sa.Integer()),
    ("line_first_pass", sa.Integer()),
    ("line_final_pass", sa.Integer()),
    ("listed", sa.Integer()),
    ("units", sa.Integer()),
    ("first_pass", sa.Integer()),
    ("final_pass", sa.Integer()),
    ("charted", sa.Integer()),
    *((f"mr_{kind}_{axis}", sa.Double()) for kind in ("offset", "sensitivity") for axis in "xyz"),
)
#: The histogram bin columns of ``report_parameters`` at this revision: h00 … h29.
HISTOGRAM_COLUMNS = tuple(f"h{i:02d}" for i in range(30))


def upgrade() -> None:
    # Plain ALTER TABLE, no batch copy: on SQLite a copy would drop ``runs`` and with it,
    # by ON DELETE CASCADE, every pose and failure reason.
    op.add_column("runs", sa.Column("lot", sa.String(length=64), nullable=True))
    op.create_index("ix_runs_lot_started_at", "runs", ["lot", "started_at", "id"], unique=False)
    op.create_table(
        "run_facts",
        sa.Column("run_pk", BigId, autoincrement=False, nullable=False),
        sa.Column("first_failure", sa.String(length=64), nullable=True),
        sa.Column("poses", sa.Integer(), nullable=False),
        sa.Column("gyro_bias_x", sa.Double(), nullable=True),
        sa.Column("gyro_bias_y", sa.Double(), nullable=True),
        sa.Column("gyro_bias_z", sa.Double(), nullable=True),
        sa.Column("line_first", sa.Boolean(), nullable=False),
        sa.Column("line_latest", sa.Boolean(), nullable=False),
        sa.Column("line_final_pass", sa.Boolean(), nullable=False),
        sa.Column("unit_runs", sa.Integer(), nullable=False),
        sa.Column("station_first", sa.Boolean(), nullable=False),
        sa.Column("station_final_pass", sa.Boolean(), nullable=False),
        sa.Column("chart_previous", BigId, nullable=True),
        sa.ForeignKeyConstraint(
            ["run_pk"], ["runs.id"], name=op.f("fk_run_facts_run_pk_runs"), ondelete="CASCADE"
        ),
        sa.PrimaryKeyConstraint("run_pk", name=op.f("pk_run_facts")),
    )
    limits = ("limits_name", "limits_version", "limits_sha256")
    op.create_table(
        "report_counts",
        *_bucket(),
        sa.Column("limits_name", sa.String(length=64), nullable=False),
        sa.Column("limits_version", sa.String(length=64), nullable=False),
        sa.Column("limits_sha256", sa.String(length=64), nullable=False),
        *(sa.Column(name, type_, nullable=False) for name, type_ in COUNT_COLUMNS),
        sa.PrimaryKeyConstraint(
            *limits, "day", "station_id", "operator_id", "lot", name=op.f("pk_report_counts")
        ),
    )
    op.create_table(
        "report_failures",
        sa.Column("code", sa.String(length=64), nullable=False),
        sa.Column("runs", sa.Integer(), nullable=False),
        *_bucket(),
        sa.PrimaryKeyConstraint(
            "code", "day", "station_id", "operator_id", "lot", name=op.f("pk_report_failures")
        ),
    )
    op.create_table(
        "report_parameters",
        sa.Column("parameter", sa.String(length=64), nullable=False),
        sa.Column("n", sa.Integer(), nullable=False),
        sa.Column("sum", sa.Double(), nullable=False),
        sa.Column("squares", sa.Double(), nullable=False),
        sa.Column("min", sa.Double(), nullable=False),
        sa.Column("max", sa.Double(), nullable=False),
        sa.Column("outside", sa.Integer(), nullable=False),
        sa.Column("marginal", sa.Integer(), nullable=False),
        *_bucket(),
        *(sa.Column(name, sa.Integer(), nullable=False) for name in HISTOGRAM_COLUMNS),
        sa.PrimaryKeyConstraint(
            "parameter",
            "day",
            "station_id",
            "operator_id",
            "lot",
            name=op.f("pk_report_parameters"),
        ),
    )
    op.create_table(
        "report_bounds",
        sa.Column("family", sa.String(length=64), nullable=False),
        sa.Column("lower", sa.Double(), nullable=True),
        sa.Column("upper", sa.Double(), nullable=True),
        sa.PrimaryKeyConstraint("family", name=op.f("pk_report_bounds")),
    )


def downgrade() -> None:
    for table in ("report_bounds", "report_parameters", "report_failures", "report_counts"):
        op.drop_table(table)
    op.drop_table("run_facts")
    op.drop_index("ix_runs_lot_started_at", table_name="runs")
    op.drop_column("runs", "lot")
