"""The product (part number) in the key of every daily roll-up.

The end-of-line report has a row per product beside the station rows. With the part
number in ``report_counts``, ``report_failures`` and ``report_parameters`` those rows add
up roll-ups as the station rows do, instead of scanning every run in range
(docs/benchmarks.md "The pages at 1,000,000 runs"). A primary key cannot change in place
on SQLite, and the roll-ups are derived data: the three tables are created anew, empty,
and ``run_facts`` is emptied, so that once the database reaches the head the facts and
roll-ups of the runs already stored are written from ``runs`` by the code of that day
(:func:`db.database.rewrite_if_stale`). The downgrade does the same without the part
number. Plain operations only: this revision does not import the project's code, so it
stays as written.

Revision ID: 0019
Revises: 0016
"""

from collections.abc import Sequence
from typing import Any

import sqlalchemy as sa
from alembic import op

revision: str = "0019"
down_revision: str | None = "0016"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: The value columns of ``report_counts`` at this revision and their types, written out.
COUNT_COLUMNS: tuple[tuple[str, sa.types.TypeEngine[Any]], ...] = (
    ("runs", sa.Integer()),
    ("runs_passed", sa.Integer()),
    ("duration_ms", sa.BigInteger()),
    ("poses", sa.Integer()),
    ("first_start", sa.DateTime(timezone=True)),
    ("last_finish", sa.DateTime(timezone=True)),
    ("line_units", sa.Integer()),
    ("line_first_pass", sa.Integer()),
    ("line_final_pass", sa.Integer()),
    ("listed", sa.Integer()),
    ("units", sa.Integer()),
    ("first_pass", sa.Integer()),
    ("final_pass", sa.Integer()),
    ("charted", sa.Integer()),
    *((f"mr_{kind}_{axis}", sa.Double()) for kind in ("offset", "sensitivity") for axis in "xyz"),
)
#: The histogram bin columns of ``report_parameters``: h00 … h29.
HISTOGRAM_COLUMNS = tuple(f"h{i:02d}" for i in range(30))
LIMITS = ("limits_name", "limits_version", "limits_sha256")
ROLLUPS = ("report_parameters", "report_failures", "report_counts")


def _create(product: bool) -> None:
    """The three roll-up tables, keyed by the part number too when ``product``."""
    key = ("day", "station_id", "operator_id", "lot", *(("part_number",) if product else ()))

    def bucket() -> list[sa.Column[Any]]:
        return [sa.Column(name, sa.String(length=64), nullable=False) for name in key[1:]]

    day = sa.Column("day", sa.Integer(), nullable=False)
    op.create_table(
        "report_counts",
        day,
        *bucket(),
        *(sa.Column(name, sa.String(length=64), nullable=False) for name in LIMITS),
        *(sa.Column(name, type_, nullable=False) for name, type_ in COUNT_COLUMNS),
        sa.PrimaryKeyConstraint(*LIMITS, *key, name=op.f("pk_report_counts")),
    )
    op.create_table(
        "report_failures",
        sa.Column("code", sa.String(length=64), nullable=False),
        sa.Column("runs", sa.Integer(), nullable=False),
        sa.Column("day", sa.Integer(), nullable=False),
        *bucket(),
        sa.PrimaryKeyConstraint("code", *key, name=op.f("pk_report_failures")),
    )
    op.create_table(
        "report_parameters",
        sa.Column("parameter", sa.String(length=64), nullable=False),
        sa.Column("n", sa.Integer(), nullable=False),
        sa.Column("sum", sa.Double(), nullable=False),
        sa.Column("squares", sa.Double(), nullable=False),
        sa.Column("min", sa.Double(), nullable=False),
        sa.Column("max", sa.Double(), nullable=False),
        sa.Column("outside", sa.Integer(), nullable=False),
        sa.Column("marginal", sa.Integer(), nullable=False),
        sa.Column("day", sa.Integer(), nullable=False),
        *bucket(),
        *(sa.Column(name, sa.Integer(), nullable=False) for name in HISTOGRAM_COLUMNS),
        sa.PrimaryKeyConstraint("parameter", *key, name=op.f("pk_report_parameters")),
    )


def _recreate(product: bool) -> None:
    for table in ROLLUPS:
        op.drop_table(table)
    # No facts beside stored runs: the upgrade to the head writes facts and roll-ups anew.
    op.execute("DELETE FROM run_facts")
    _create(product)


def upgrade() -> None:
    _recreate(product=True)


def downgrade() -> None:
    _recreate(product=False)
