"""Gyro error-model fits per unit.

Revision ID: 0002
Revises: 0001
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op
from sqlalchemy.dialects import postgresql

revision: str = "0002"
down_revision: str | None = "0001"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: The DDL types of :mod:`db.base`, written out: a migration imports no project code, so
#: editing db/ never changes what this revision creates.
UtcDateTime = sa.DateTime(timezone=True)
JsonDocument = sa.JSON().with_variant(postgresql.JSONB(), "postgresql")


def upgrade() -> None:
    op.create_table(
        "gyro_fits",
        sa.Column(
            "id",
            sa.BigInteger().with_variant(sa.Integer(), "sqlite"),
            autoincrement=True,
            nullable=False,
        ),
        sa.Column("serial", sa.String(length=64), nullable=False),
        sa.Column("fitted_at", UtcDateTime, nullable=False),
        sa.Column("source", sa.String(length=255), nullable=False),
        sa.Column("document", JsonDocument, nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_gyro_fits")),
    )
    with op.batch_alter_table("gyro_fits", schema=None) as batch_op:
        batch_op.create_index(
            "ix_gyro_fits_serial_fitted_at", ["serial", "fitted_at", "id"], unique=False
        )


def downgrade() -> None:
    with op.batch_alter_table("gyro_fits", schema=None) as batch_op:
        batch_op.drop_index("ix_gyro_fits_serial_fitted_at")
    op.drop_table("gyro_fits")
