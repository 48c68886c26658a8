"""The fixture slot of every run: ``runs.fixture_slot`` (runs stored before it: none);
the alerts that fired: ``alerts``.

A station records the slot of its fixture each run was calibrated in, from 1 (a one-port
station is a fixture of one slot: 1), so the report can split a parameter by slot. Runs
stored before this revision do not say: their slot stays empty (NULL), never guessed.
The alerts a plant's rules fired are stored once per event (``event_key`` unique), at
most one open per rule (a partial unique index). Plain operations only: this revision
does not import the project's code, so it stays as written.

Revision ID: 0015
Revises: 0014
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op
from sqlalchemy.dialects import postgresql

revision: str = "0015"
down_revision: str | None = "0014"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: The DDL type of :mod:`db.base`, written out (a migration imports no project code).
UtcDateTime = sa.DateTime(timezone=True)


def upgrade() -> None:
    # A nullable column without a default: added in place on SQLite and PostgreSQL alike
    # (no copy of ``runs``, no rewrite of its rows).
    op.add_column("runs", sa.Column("fixture_slot", sa.Integer(), nullable=True))
    json = sa.JSON().with_variant(postgresql.JSONB(), "postgresql")
    op.create_table(
        "alerts",
        sa.Column("id", sa.BigInteger().with_variant(sa.Integer(), "sqlite"), nullable=False),
        sa.Column("event_key", sa.String(length=255), nullable=False),
        sa.Column("watch", sa.String(length=255), nullable=False),
        sa.Column("rule", sa.String(length=16), nullable=False),
        sa.Column("scope", sa.String(length=64), nullable=False),
        sa.Column("message", sa.Text(), nullable=False),
        sa.Column("evidence", json, nullable=False),
        sa.Column("fired_at", UtcDateTime, nullable=False),
        sa.Column("cleared_at", UtcDateTime, nullable=True),
        sa.Column("delivered_at", UtcDateTime, nullable=True),
        sa.Column("attempts", sa.Integer(), nullable=False),
        sa.Column("next_attempt_at", UtcDateTime, nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_alerts")),
        sa.UniqueConstraint("event_key", name=op.f("uq_alerts_event_key")),
    )
    op.create_index(
        "ux_alerts_open_watch",
        "alerts",
        ["watch"],
        unique=True,
        sqlite_where=sa.text("cleared_at IS NULL"),
        postgresql_where=sa.text("cleared_at IS NULL"),
    )
    op.create_index("ix_alerts_fired_at", "alerts", ["fired_at", "id"])


def downgrade() -> None:
    op.drop_index("ix_alerts_fired_at", table_name="alerts")
    op.drop_index("ux_alerts_open_watch", table_name="alerts")
    op.drop_table("alerts")
    op.drop_column("runs", "fixture_slot")
