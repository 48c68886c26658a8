"""Limits profiles stored in the database (``limits_profiles``), keyed by their SHA-256.

A run's submission carries its profile's canonical JSON, stored the first time a run
uses it; ``runs.limits_sha256`` refers to it (no foreign key: runs stored before this
revision refer to profiles whose content the server never received, and SQLite could
add the key only by copying ``runs``, whose drop would cascade to every pose).

Runs stored before this revision: when they used the profile the station shipped with
until now (``kxm52-production`` v1), its document is stored here, copied as text below
(its SHA-256 is the one those runs carry); other profiles stay unknown until a station
sends them. Plain operations only: this revision does not import the project's code, so it stays as
written.

Revision ID: 0007
Revises: 0006
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0007"
down_revision: str | None = "0006"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: The shipped ``kxm52-production`` v1 profile as the runs before this revision hashed it.
SHIPPED_SHA256 = "e905f35844e7fbe48d498e538a70a61ff222e6cc049d0f477fc8f0d958c66800"
SHIPPED_DOCUMENT = (
    '{"description":"KXM52-1050 behind the ADS7829, datasheet bounds over -40\\u2026125 '
    '\\u00b0C","gyro_bias_dps":{"lower":-10.0,"upper":10.0},"link_loss":{"lower":null,'
    '"upper":0.01},"name":"kxm52-production","offset_counts":{"lower":1841.0,"upper":2255.0},'
    '"pose_noise_counts":{"lower":null,"upper":8.0},"sensitivity_counts_per_g":{"lower":'
    '778.24,"upper":860.16},"verification_error_mg":{"lower":null,"upper":30.0},"version":'
    '"1","writeback_relative_error":{"lower":null,"upper":1e-06}}'
)


def upgrade() -> None:
    op.create_table(
        "limits_profiles",
        sa.Column("sha256", sa.String(length=64), nullable=False),
        sa.Column("name", sa.String(length=64), nullable=False),
        sa.Column("version", sa.String(length=64), nullable=False),
        sa.Column("document", sa.Text(), nullable=False),
        sa.PrimaryKeyConstraint("sha256", name=op.f("pk_limits_profiles")),
    )
    op.execute(
        sa.text(
            "INSERT INTO limits_profiles (sha256, name, version, document) "
            "SELECT :sha256, 'kxm52-production', '1', :document "
            "WHERE EXISTS (SELECT 1 FROM runs WHERE limits_sha256 = :sha256)"
        ).bindparams(sha256=SHIPPED_SHA256, document=SHIPPED_DOCUMENT)
    )


def downgrade() -> None:
    op.drop_table("limits_profiles")
