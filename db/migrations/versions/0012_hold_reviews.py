"""Quality reviews of units on hold (``hold_reviews``), and API keys of scope ``quality``.

A unit whose latest run sent it to rework is not calibrated again until a quality
engineer reviews it: the root cause, the repair, and the decision (``retest`` or
``scrap``), append-only. Keys of scope ``quality`` store reviews. Plain operations only:
this revision does not import the project's code, so it stays as written.

Revision ID: 0012
Revises: 0011
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0012"
down_revision: str | None = "0011"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: The DDL type of :mod:`db.base`, written out (a migration imports no project code).
UtcDateTime = sa.DateTime(timezone=True)


def upgrade() -> None:
    op.create_table(
        "hold_reviews",
        sa.Column(
            "id",
            sa.BigInteger().with_variant(sa.Integer(), "sqlite"),
            autoincrement=True,
            nullable=False,
        ),
        sa.Column("serial", sa.String(length=64), nullable=False),
        sa.Column("run_id", sa.Uuid(), nullable=False),
        sa.Column("reviewed_at", UtcDateTime, nullable=False),
        sa.Column("reviewer", sa.String(length=64), nullable=False),
        sa.Column("root_cause", sa.Text(), nullable=False),
        sa.Column("repair_action", sa.Text(), nullable=False),
        sa.Column("decision", sa.String(length=8), nullable=False),
        sa.CheckConstraint(
            "decision IN ('retest', 'scrap')", name=op.f("ck_hold_reviews_decision")
        ),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_hold_reviews")),
    )
    with op.batch_alter_table("hold_reviews", schema=None) as batch_op:
        batch_op.create_index(
            "ix_hold_reviews_serial_reviewed_at", ["serial", "reviewed_at", "id"], unique=False
        )
    with op.batch_alter_table("station_keys", schema=None) as batch_op:
        batch_op.drop_constraint(op.f("ck_station_keys_scope"), type_="check")
        batch_op.create_check_constraint(
            op.f("ck_station_keys_scope"), "scope IN ('station', 'lab', 'quality')"
        )


def downgrade() -> None:
    with op.batch_alter_table("station_keys", schema=None) as batch_op:
        batch_op.drop_constraint(op.f("ck_station_keys_scope"), type_="check")
        batch_op.create_check_constraint(
            op.f("ck_station_keys_scope"), "scope IN ('station', 'lab')"
        )
    with op.batch_alter_table("hold_reviews", schema=None) as batch_op:
        batch_op.drop_index("ix_hold_reviews_serial_reviewed_at")
    op.drop_table("hold_reviews")
