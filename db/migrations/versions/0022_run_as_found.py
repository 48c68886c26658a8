"""The coefficients a unit held before its run wrote its own (``runs.as_found``, one JSON
document: ``{"read_at", "accelerometer": {"written", "offset", "matrix"}, "gyro": …}``):
the as-found values of a calibration certificate (ISO/IEC 17025:2017 7.8.4.1).

Runs stored before this revision were not read before write-back: null, which the
certificate shows as "not recorded". Plain operations only: this revision does not import
the project's code, so it stays as written.

Revision ID: 0022
Revises: 0021
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op
from sqlalchemy.dialects import postgresql

revision: str = "0022"
down_revision: str | None = "0021"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

JsonDocument = sa.JSON().with_variant(postgresql.JSONB(astext_type=sa.Text()), "postgresql")


def upgrade() -> None:
    op.add_column("runs", sa.Column("as_found", JsonDocument, nullable=True))


def downgrade() -> None:
    op.drop_column("runs", "as_found")
