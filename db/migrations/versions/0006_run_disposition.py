"""Where the station sent each unit (``runs.disposition``: ship, retest or rework).

Runs stored before this revision have none (null). Plain operations only: this
revision does not import the project's code, so it stays as written.

Revision ID: 0006
Revises: 0005
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0006"
down_revision: str | None = "0005"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


#: The column as SQLite adds it in place. A batch migration would copy ``runs`` and drop
#: the old table, and with foreign keys on, that drop cascades to every pose, failure and
#: unit answer of every run: SQLite's own ``ADD COLUMN`` (with a column CHECK) and ``DROP
#: COLUMN`` keep the table.
_SQLITE_ADD = (
    "ALTER TABLE runs ADD COLUMN disposition VARCHAR(8) CONSTRAINT ck_runs_disposition "
    "CHECK (disposition IN ('ship', 'retest', 'rework'))"
)


def upgrade() -> None:
    if op.get_bind().dialect.name == "sqlite":
        op.execute(_SQLITE_ADD)
        return
    op.add_column("runs", sa.Column("disposition", sa.String(length=8), nullable=True))
    op.create_check_constraint(
        op.f("ck_runs_disposition"), "runs", "disposition IN ('ship', 'retest', 'rework')"
    )


def downgrade() -> None:
    if op.get_bind().dialect.name != "sqlite":
        op.drop_constraint(op.f("ck_runs_disposition"), "runs", type_="check")
    op.drop_column("runs", "disposition")
