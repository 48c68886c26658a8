"""The fixture slot of every run: ``runs.fixture_slot`` (runs stored before it: none).

A station records the slot of its fixture each run was calibrated in, from 1 (a one-port
station is a fixture of one slot: 1), so the report can split a parameter by slot. Runs
stored before this revision do not say: their slot stays empty (NULL), never guessed.
Plain operations only: this revision does not import the project's code, so it stays as
written.

Revision ID: 0015
Revises: 0014
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0015"
down_revision: str | None = "0014"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    # A nullable column without a default: added in place on SQLite and PostgreSQL alike
    # (no copy of ``runs``, no rewrite of its rows).
    op.add_column("runs", sa.Column("fixture_slot", sa.Integer(), nullable=True))


def downgrade() -> None:
    op.drop_column("runs", "fixture_slot")
