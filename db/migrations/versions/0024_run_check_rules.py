"""The decision rule that judged each limit of a run (``runs.check_rules``, one JSON
document: ``{"offset": "guarded", "gyro_scale": "guarded", "pose_noise": "simple", …}``,
by check code).

Guarded acceptance (ILAC-G8:09/2019 §4.2.2) judges every value that carries its expanded
uncertainty U: the accelerometer's coefficients, the gyro biases, the gyro matrix K's
entries and the verification pose's error. Runs stored before this revision were judged
under their ``decision_rule`` for the offsets, sensitivities and gyro biases only, every
other limit by simple acceptance: they keep NULL here, which says so (the record reads it
as that rule), and their records keep the JSON they were signed with. Plain operations
only: this revision does not import the project's code, so it stays as written.

Revision ID: 0024
Revises: 0023
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op
from sqlalchemy.dialects import postgresql

revision: str = "0024"
down_revision: str | None = "0023"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

JsonDocument = sa.JSON().with_variant(postgresql.JSONB(astext_type=sa.Text()), "postgresql")


def upgrade() -> None:
    # A nullable column without a default: SQLite adds it in place, no batch copy.
    op.add_column("runs", sa.Column("check_rules", JsonDocument, nullable=True))


def downgrade() -> None:
    op.drop_column("runs", "check_rules")
