"""A failure's expanded uncertainty U: ``run_failures.uncertainty``.

Guarded acceptance (ILAC-G8:09/2019 §4.2.2) refuses a value inside its bounds when it
lies nearer a bound than its expanded uncertainty U. The station's sentence names U;
the reader's language renders the failure from its stored parameters
(``station/report/explanations.py``), so U is stored beside the value and the bounds.
Failures stored before this revision have none (NULL). Plain operations only: this
revision does not import the project's code, so it stays as written.

Revision ID: 0016
Revises: 0015
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0016"
down_revision: str | None = "0015"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    # A nullable column without a default: SQLite adds it in place, no batch copy.
    op.add_column("run_failures", sa.Column("uncertainty", sa.Double(), nullable=True))


def downgrade() -> None:
    op.drop_column("run_failures", "uncertainty")
