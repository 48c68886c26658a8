"""Why a run was made (``runs.purpose``): null for a production unit, ``golden`` for the
station's golden-unit check, which the report does not count as a unit.

Runs stored before this revision are production runs (null). Plain operations only:
this revision does not import the project's code, so it stays as written.

Revision ID: 0009
Revises: 0007
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0009"
down_revision: str | None = "0007"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


#: The column as SQLite adds it in place (as 0006 does: a batch migration would copy
#: ``runs`` and its drop would cascade to every pose, failure and unit answer).
_SQLITE_ADD = (
    "ALTER TABLE runs ADD COLUMN purpose VARCHAR(8) CONSTRAINT ck_runs_purpose "
    "CHECK (purpose IN ('golden'))"
)


def upgrade() -> None:
    if op.get_bind().dialect.name == "sqlite":
        op.execute(_SQLITE_ADD)
        return
    op.add_column("runs", sa.Column("purpose", sa.String(length=8), nullable=True))
    op.create_check_constraint(op.f("ck_runs_purpose"), "runs", "purpose IN ('golden')")


def downgrade() -> None:
    if op.get_bind().dialect.name != "sqlite":
        op.drop_constraint(op.f("ck_runs_purpose"), "runs", type_="check")
    op.drop_column("runs", "purpose")
