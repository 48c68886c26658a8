"""The product of every run: ``runs.part_number`` (runs stored before it: DIXX-A12).

A line builds more than one product (``station/domain/product/products.py``); each run records
the part number of the unit's product. Every run stored before this revision was of the
one product there was, the putter with the KXM52 behind a 12-bit ADC: DIXX-A12. The
units' answers gain the field too; the upgrade rewrites them (``db/database.py``). Plain
operations only: this revision does not import the project's code, so it stays as
written.

Revision ID: 0014
Revises: 0013
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0014"
down_revision: str | None = "0013"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: The part number of every run stored before this revision.
FIRST_PRODUCT = "DIXX-A12"


#: The column as SQLite adds it in place (as 0006 and 0009 do: a batch migration would
#: copy ``runs`` and its drop would cascade to every pose, failure and unit answer). The
#: default stays on SQLite (it cannot drop one in place); every new row names its product.
_SQLITE_ADD = (
    f"ALTER TABLE runs ADD COLUMN part_number VARCHAR(64) NOT NULL DEFAULT '{FIRST_PRODUCT}'"
)


def upgrade() -> None:
    if op.get_bind().dialect.name == "sqlite":
        op.execute(_SQLITE_ADD)
    else:
        op.add_column(
            "runs",
            sa.Column(
                "part_number", sa.String(length=64), nullable=False, server_default=FIRST_PRODUCT
            ),
        )
        # The default filled the rows already stored; new rows always name their product.
        op.alter_column("runs", "part_number", server_default=None)
    op.create_index("ix_runs_part_number_started_at", "runs", ["part_number", "started_at", "id"])


def downgrade() -> None:
    op.drop_index("ix_runs_part_number_started_at", table_name="runs")
    op.drop_column("runs", "part_number")
