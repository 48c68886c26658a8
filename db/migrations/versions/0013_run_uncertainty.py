"""The expanded uncertainties of a run's coefficients (``runs.uncertainty``, one JSON
document: ``{"k", "offset", "sensitivity", "gyro_bias_dps", "gyro_matrix"}``) and the
decision rule that judged it (``runs.decision_rule``: ``simple`` or ``guarded``).

Runs stored before this revision have neither (null: they were judged by simple
acceptance). SQLite adds the columns in place (a batch migration would copy ``runs`` and
its drop would cascade to every pose). Plain operations only: this revision does not
import the project's code, so it stays as written.

Revision ID: 0013
Revises: 0012
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op
from sqlalchemy.dialects import postgresql

revision: str = "0013"
down_revision: str | None = "0012"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

JsonDocument = sa.JSON().with_variant(postgresql.JSONB(astext_type=sa.Text()), "postgresql")

#: The rule column as SQLite adds it in place (as 0009 adds ``purpose``).
_SQLITE_ADD_RULE = (
    "ALTER TABLE runs ADD COLUMN decision_rule VARCHAR(8) CONSTRAINT ck_runs_decision_rule "
    "CHECK (decision_rule IN ('simple', 'guarded'))"
)


def upgrade() -> None:
    op.add_column("runs", sa.Column("uncertainty", JsonDocument, nullable=True))
    if op.get_bind().dialect.name == "sqlite":
        op.execute(_SQLITE_ADD_RULE)
        return
    op.add_column("runs", sa.Column("decision_rule", sa.String(length=8), nullable=True))
    op.create_check_constraint(
        op.f("ck_runs_decision_rule"), "runs", "decision_rule IN ('simple', 'guarded')"
    )


def downgrade() -> None:
    if op.get_bind().dialect.name != "sqlite":
        op.drop_constraint(op.f("ck_runs_decision_rule"), "runs", type_="check")
    op.drop_column("runs", "decision_rule")
    op.drop_column("runs", "uncertainty")
