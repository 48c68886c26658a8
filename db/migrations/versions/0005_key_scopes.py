"""What an API key may do (``station_keys.scope``): store its station's runs, or lab fits.

A ``station`` key stores runs of its own station; a ``lab`` key stores units' gyro
fits. Every key created before this revision is a station key. Plain operations only:
this revision does not import the project's code, so it stays as written.

Revision ID: 0005
Revises: 0004
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0005"
down_revision: str | None = "0004"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None


def upgrade() -> None:
    with op.batch_alter_table("station_keys", schema=None) as batch_op:
        batch_op.add_column(
            sa.Column("scope", sa.String(length=8), nullable=False, server_default="station")
        )
        batch_op.create_check_constraint(
            op.f("ck_station_keys_scope"), "scope IN ('station', 'lab')"
        )


def downgrade() -> None:
    with op.batch_alter_table("station_keys", schema=None) as batch_op:
        batch_op.drop_constraint(op.f("ck_station_keys_scope"), type_="check")
        batch_op.drop_column("scope")
