"""Each unit's current calibration, ready to serve (``units``).

The schema only: the answers about the units already stored are derived data, written
once the database reaches the head (:func:`db.database.rewrite_if_stale`).

Revision ID: 0004
Revises: 0003
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0004"
down_revision: str | None = "0003"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: The DDL type of :class:`db.base.UtcDateTime`, written out: a migration imports no project
#: code, so editing db/ never changes what this revision creates.
UtcDateTime = sa.DateTime(timezone=True)


def upgrade() -> None:
    op.create_table(
        "units",
        sa.Column("serial", sa.String(length=64), nullable=False),
        sa.Column(
            "run_pk",
            sa.BigInteger().with_variant(sa.Integer(), "sqlite"),
            nullable=False,
        ),
        sa.Column("started_at", UtcDateTime, nullable=False),
        sa.Column("calibration", sa.Text(), nullable=False),
        sa.ForeignKeyConstraint(
            ["run_pk"], ["runs.id"], name=op.f("fk_units_run_pk_runs"), ondelete="CASCADE"
        ),
        sa.PrimaryKeyConstraint("serial", name=op.f("pk_units")),
    )


def downgrade() -> None:
    op.drop_table("units")
