"""Authorised signatories (``signatories``: a name and the public half of their Ed25519
key) and their signatures of certificates (``certificate_signatures``: one per run, the
number, the record's SHA-256, who, when and the signature). Plain operations only: this
revision does not import the project's code, so it stays as written.

Revision ID: 0023
Revises: 0022
"""

from collections.abc import Sequence

import sqlalchemy as sa
from alembic import op

revision: str = "0023"
down_revision: str | None = "0022"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

#: The DDL types of :mod:`db.base`, written out (a migration imports no project code).
BigId = sa.BigInteger().with_variant(sa.Integer(), "sqlite")
UtcDateTime = sa.DateTime(timezone=True)


def upgrade() -> None:
    op.create_table(
        "signatories",
        sa.Column("id", BigId, autoincrement=True, nullable=False),
        sa.Column("name", sa.String(length=64), nullable=False),
        sa.Column("public_key", sa.String(length=64), nullable=False),
        sa.Column("created_at", UtcDateTime, nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_signatories")),
        sa.UniqueConstraint("name", name=op.f("uq_signatories_name")),
    )
    op.create_table(
        "certificate_signatures",
        sa.Column("id", BigId, autoincrement=True, nullable=False),
        sa.Column("run_id", sa.Uuid(), nullable=False),
        sa.Column("certificate", sa.String(length=64), nullable=False),
        sa.Column("record_sha256", sa.String(length=64), nullable=False),
        sa.Column("signatory", sa.String(length=64), nullable=False),
        sa.Column("signed_at", UtcDateTime, nullable=False),
        sa.Column("signature", sa.String(length=128), nullable=False),
        sa.PrimaryKeyConstraint("id", name=op.f("pk_certificate_signatures")),
        sa.UniqueConstraint("run_id", name=op.f("uq_certificate_signatures_run_id")),
    )


def downgrade() -> None:
    op.drop_table("certificate_signatures")
    op.drop_table("signatories")
