"""The poses a run's solve left out (``runs.excluded_poses``): the 0-based indexes of the
fit poses found inconsistent with the others and excluded ([Song2006] least squares with
eight or more poses; ``station.domain.calibration.consistency``), as a JSON list; null when the
solve left none out.

Runs stored before this revision left none out. SQLite adds the column in place (a batch
migration would copy ``runs`` and its drop would cascade to every pose). Plain
operations only: this revision does not import the project's code, so it stays as
written.

Revision ID: 0010
Revises: 0009
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op
from sqlalchemy.dialects import postgresql

revision: str = "0010"
down_revision: str | None = "0009"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

JsonDocument = sa.JSON().with_variant(postgresql.JSONB(astext_type=sa.Text()), "postgresql")


def upgrade() -> None:
    op.add_column("runs", sa.Column("excluded_poses", JsonDocument, nullable=True))


def downgrade() -> None:
    op.drop_column("runs", "excluded_poses")
