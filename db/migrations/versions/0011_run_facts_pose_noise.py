"""Each run's pose noise summed over its poses (``run_facts.noise_sum_*`` and
``noise_squares_*``: Σ std and Σ std² per axis over the run's poses), so that a trend's
capability of the pose noise reads one row per run instead of its every pose
(``db.rollups``; the report page in a plant time zone or with shifts, docs/benchmarks.md
"report").

The sums of the runs stored before this revision are computed here from ``poses`` in
plain SQL. Plain operations only: this revision does not import the project's code, so
it stays as written.

Revision ID: 0011
Revises: 0010
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0011"
down_revision: str | None = "0010"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

AXES = ("x", "y", "z")


def upgrade() -> None:
    for axis in AXES:
        op.add_column("run_facts", sa.Column(f"noise_sum_{axis}", sa.Double(), nullable=True))
        op.add_column("run_facts", sa.Column(f"noise_squares_{axis}", sa.Double(), nullable=True))
    sums = ", ".join(
        f"noise_sum_{a} = (SELECT sum(std_{a}) FROM poses WHERE poses.run_pk = run_facts.run_pk), "
        f"noise_squares_{a} = (SELECT sum(std_{a} * std_{a}) FROM poses "
        "WHERE poses.run_pk = run_facts.run_pk)"
        for a in AXES
    )
    op.execute(f"UPDATE run_facts SET {sums}")


def downgrade() -> None:
    for axis in AXES:
        op.drop_column("run_facts", f"noise_squares_{axis}")
        op.drop_column("run_facts", f"noise_sum_{axis}")
