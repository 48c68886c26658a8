"""One yield definition: attempts, retests and aborts in the facts and roll-ups.

A unit's first and latest run are now its first and latest *attempt* (a run the operator
did not abort), and each attempt that is not its unit's first is a retest at its own
station (not a station's runs less the cohort's units, which counted other stations' units).
``run_facts`` gains ``attempt`` and loses ``station_first`` and ``station_final_pass``
(counts per station of a unit's first run there, which no figure read); ``report_counts``
gains ``retests`` and ``aborts`` and loses ``listed``, ``units``, ``first_pass`` and
``final_pass`` (their sums). The facts and counts of the runs already stored change
meaning: both tables are emptied, so that once the database reaches the head they are
written anew from ``runs`` by the code of that day (:func:`db.database.rewrite_if_stale`,
as after revision 0019). The downgrade does the same with the old columns. Plain
operations only: this revision does not import the project's code, so it stays as
written.

Revision ID: 0021
Revises: 0020
"""

from collections.abc import Sequence
from typing import Any

import sqlalchemy as sa
from alembic import op

revision: str = "0021"
down_revision: str | None = "0020"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: The columns each revision has that the other has not: (table, name, type).
Columns = tuple[tuple[str, str, sa.types.TypeEngine[Any]], ...]
NEW: Columns = (
    ("run_facts", "attempt", sa.Boolean()),
    ("report_counts", "retests", sa.Integer()),
    ("report_counts", "aborts", sa.Integer()),
)
OLD: Columns = (
    ("run_facts", "station_first", sa.Boolean()),
    ("run_facts", "station_final_pass", sa.Boolean()),
    ("report_counts", "listed", sa.Integer()),
    ("report_counts", "units", sa.Integer()),
    ("report_counts", "first_pass", sa.Integer()),
    ("report_counts", "final_pass", sa.Integer()),
)


def _swap(added: Columns, dropped: Columns) -> None:
    # Derived rows only: written anew from the runs once the database is at the head.
    for table in ("report_counts", "run_facts"):
        op.execute(f"DELETE FROM {table}")
        with op.batch_alter_table(table) as batch:
            for name in (name for t, name, _ in dropped if t == table):
                batch.drop_column(name)
            for name, type_ in ((name, type_) for t, name, type_ in added if t == table):
                batch.add_column(sa.Column(name, type_, nullable=False))


def upgrade() -> None:
    _swap(NEW, OLD)


def downgrade() -> None:
    _swap(OLD, NEW)
