"""Each station's latest outbox report: ``station_outboxes``.

A station sends its outbox's state with every run (the ``Calstation-Outbox`` header of
``POST /api/v1/runs``: runs queued behind it, the oldest one's wait, files set aside);
the server keeps the latest per station, written with the run, for the ``[[outbox]]``
alert rule. Plain operations only: this revision does not import the project's code,
so it stays as written.

Revision ID: 0020
Revises: 0019
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0020"
down_revision: str | None = "0019"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: The DDL type of :mod:`db.base`, written out (a migration imports no project code).
UtcDateTime = sa.DateTime(timezone=True)


def upgrade() -> None:
    op.create_table(
        "station_outboxes",
        sa.Column("station_id", sa.String(length=64), nullable=False),
        sa.Column("queued", sa.Integer(), nullable=False),
        sa.Column("oldest_s", sa.Integer(), nullable=False),
        sa.Column("set_aside", sa.Integer(), nullable=False),
        sa.Column("reported_at", UtcDateTime, nullable=False),
        sa.PrimaryKeyConstraint("station_id", name=op.f("pk_station_outboxes")),
    )


def downgrade() -> None:
    op.drop_table("station_outboxes")
