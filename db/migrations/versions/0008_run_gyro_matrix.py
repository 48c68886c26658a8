"""The gyro matrix of a run (``runs.gyro_matrix``): K, its standard errors, the bias and
each move's residual, as one JSON document (whole-unit runs; null otherwise).

Runs stored before this revision have none. SQLite adds the column in place (a batch
migration would copy ``runs`` and its drop would cascade to every pose). Plain
operations only: this revision does not import the project's code, so it stays as
written.

Revision ID: 0008
Revises: 0007
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op
from sqlalchemy.dialects import postgresql

revision: str = "0008"
down_revision: str | None = "0007"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

JsonDocument = sa.JSON().with_variant(postgresql.JSONB(astext_type=sa.Text()), "postgresql")


def upgrade() -> None:
    op.add_column("runs", sa.Column("gyro_matrix", JsonDocument, nullable=True))


def downgrade() -> None:
    op.drop_column("runs", "gyro_matrix")
