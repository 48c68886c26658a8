"""The register of runs (``run_ids``), and on PostgreSQL ``runs`` and ``poses``
partitioned by year of ``started_at``.

``run_ids`` holds each run's UUID, its key (``run_pk``, from the sequence that numbered
``runs.id``) and its start: the UUID's uniqueness, on which a submission's idempotency
rests, lives there, so ``runs`` need not carry a unique constraint of its own. Every table
that belonged to a run (``runs`` itself, ``poses``, ``run_failures``, ``run_facts``,
``units``) now refers to ``run_ids``; nothing refers to ``runs``. ``poses`` gets its run's
``started_at``.

PostgreSQL requires every unique constraint of a partitioned table to hold the partition
key, and a foreign key onto one to name it; with the references on ``run_ids`` neither
is needed, and ``runs`` and ``poses`` become tables partitioned by range of
``started_at``: one partition a calendar year (UTC, ``runs_2026``) for each year that
holds runs, the current one and the next, and a ``runs_default`` / ``poses_default`` for
any start outside them. Their primary keys become ``(id, started_at)``. ``calstation db
partitions`` creates the years ahead as time goes on
(:mod:`db.partitions`). SQLite keeps plain tables. Plain operations only: this revision
does not import the project's code, so it stays as written.

Revision ID: 0025
Revises: 0024
"""

import re
from collections.abc import Sequence
from datetime import UTC, datetime

import sqlalchemy as sa
from alembic import op

revision: str = "0025"
down_revision: str | None = "0024"
branch_labels: str | Sequence[str] | None = None
depends_on: str | Sequence[str] | None = None

BigId = sa.BigInteger().with_variant(sa.Integer(), "sqlite")
UtcDateTime = sa.DateTime(timezone=True)
#: The tables that refer to a run by ``run_pk``, besides ``poses``.
CHILDREN = ("run_failures", "run_facts", "units")
#: Years created past the current one.
AHEAD = 1
#: ``runs``' secondary indexes, as the models name them.
RUN_INDEXES = {
    "ix_runs_serial_started_at": "serial, started_at, id",
    "ix_runs_station_id_started_at": "station_id, started_at, id",
    "ix_runs_verdict_started_at": "verdict, started_at, id",
    "ix_runs_started_at": "started_at, id",
    "ix_runs_lot_started_at": "lot, started_at, id",
    "ix_runs_part_number_started_at": "part_number, started_at, id",
}

#: Each year that holds runs, in UTC.
YEARS = """
SELECT DISTINCT CAST(extract(year FROM started_at AT TIME ZONE 'UTC') AS integer) FROM runs
"""


def upgrade() -> None:
    op.create_table(
        "run_ids",
        # Numbered by the sequence that numbered runs.id (PostgreSQL; SQLite: its rowid).
        sa.Column("run_pk", BigId, autoincrement=False, nullable=False),
        sa.Column("run_id", sa.Uuid(), nullable=False),
        sa.Column("started_at", UtcDateTime, nullable=False),
        sa.PrimaryKeyConstraint("run_pk", name=op.f("pk_run_ids")),
        sa.UniqueConstraint("run_id", name=op.f("uq_run_ids_run_id")),
    )
    op.execute(
        "INSERT INTO run_ids (run_pk, run_id, started_at) SELECT id, run_id, started_at FROM runs"
    )
    op.add_column("poses", sa.Column("started_at", UtcDateTime, nullable=True))
    op.execute(
        "UPDATE poses SET started_at = (SELECT started_at FROM runs WHERE runs.id = poses.run_pk)"
    )
    if op.get_bind().dialect.name == "postgresql":
        _partition()
        return
    # SQLite: the children first, so that no table refers to ``runs`` when it is copied.
    for table in CHILDREN:
        with op.batch_alter_table(table) as batch:
            batch.drop_constraint(f"fk_{table}_run_pk_runs", type_="foreignkey")
            batch.create_foreign_key(
                f"fk_{table}_run_pk_run_ids", "run_ids", ["run_pk"], ["run_pk"], ondelete="CASCADE"
            )
    with op.batch_alter_table("poses") as batch:
        batch.alter_column("started_at", existing_type=UtcDateTime, nullable=False)
        batch.drop_constraint("uq_poses_run_pk_index", type_="unique")
        batch.create_unique_constraint(
            "uq_poses_run_pk_index_started_at", ["run_pk", "index", "started_at"]
        )
        batch.drop_constraint("fk_poses_run_pk_runs", type_="foreignkey")
        batch.create_foreign_key(
            "fk_poses_run_pk_run_ids", "run_ids", ["run_pk"], ["run_pk"], ondelete="CASCADE"
        )
    _rebuild_sqlite_runs(UNIQUE_RUN_ID, REFERENCE_TO_REGISTER)


#: ``runs``' constraint before this revision and after it, as SQLite's schema spells them.
UNIQUE_RUN_ID = "CONSTRAINT uq_runs_run_id UNIQUE (run_id)"
REFERENCE_TO_REGISTER = (
    "CONSTRAINT fk_runs_id_run_ids FOREIGN KEY(id) REFERENCES run_ids (run_pk) ON DELETE CASCADE"
)


def _rebuild_sqlite_runs(old: str, new: str) -> None:
    """SQLite: copy ``runs`` into a table of its own definition with constraint ``old``
    made ``new`` (SQLite alters no constraint in place).

    Not Alembic's batch mode: its copy would turn the CHECK of each column a revision
    added into a table constraint, and an older revision's downgrade could then no longer
    drop the column in place. Nothing refers to ``runs`` while it is copied (the tables
    that did refer to ``run_ids`` by then), so dropping it deletes no other row.
    """
    bind = op.get_bind()
    table = bind.scalar(
        sa.text("SELECT sql FROM sqlite_master WHERE type = 'table' AND name = 'runs'")
    )
    indexes = bind.scalars(
        sa.text(
            "SELECT sql FROM sqlite_master "
            "WHERE type = 'index' AND tbl_name = 'runs' AND sql IS NOT NULL"
        )
    ).all()
    assert old in table, f"runs is not as revision 0025 expects it: {table}"
    op.execute(
        re.sub(r'^CREATE TABLE "?runs"? \(', "CREATE TABLE runs_copy (", table).replace(old, new)
    )
    op.execute("INSERT INTO runs_copy SELECT * FROM runs")
    op.execute("DROP TABLE runs")
    op.execute("ALTER TABLE runs_copy RENAME TO runs")
    for index in indexes:
        op.execute(index)


def _partition() -> None:
    """PostgreSQL: move the references onto ``run_ids``, rebuild ``runs`` and ``poses``
    partitioned by year, copy the rows over and drop the old tables."""
    # run_ids numbers the runs from now on, with the sequence that numbered them.
    op.execute("ALTER SEQUENCE runs_id_seq OWNED BY NONE")
    op.execute("ALTER SEQUENCE runs_id_seq RENAME TO run_ids_run_pk_seq")
    op.execute("ALTER TABLE run_ids ALTER COLUMN run_pk SET DEFAULT nextval('run_ids_run_pk_seq')")
    op.execute("ALTER SEQUENCE run_ids_run_pk_seq OWNED BY run_ids.run_pk")
    op.execute("ALTER TABLE runs ALTER COLUMN id DROP DEFAULT")
    op.execute(
        "SELECT setval('run_ids_run_pk_seq', GREATEST((SELECT max(run_pk) FROM run_ids), 1))"
    )
    for table in CHILDREN:
        op.execute(f"ALTER TABLE {table} DROP CONSTRAINT fk_{table}_run_pk_runs")
        op.execute(
            f"ALTER TABLE {table} ADD CONSTRAINT fk_{table}_run_pk_run_ids FOREIGN KEY (run_pk) "
            "REFERENCES run_ids (run_pk) ON DELETE CASCADE"
        )
    op.execute("ALTER SEQUENCE poses_id_seq OWNED BY NONE")
    for table in ("runs", "poses"):
        op.execute(
            f"CREATE TABLE {table}_by_year (LIKE {table} INCLUDING DEFAULTS "
            "INCLUDING CONSTRAINTS) PARTITION BY RANGE (started_at)"
        )
    op.execute("ALTER TABLE poses_by_year ALTER COLUMN started_at SET NOT NULL")
    current = datetime.now(UTC).year
    years = {*op.get_bind().scalars(sa.text(YEARS)), *range(current, current + AHEAD + 1)}
    for year in sorted(years):
        for table in ("runs", "poses"):
            op.execute(
                f"CREATE TABLE {table}_{year:04d} PARTITION OF {table}_by_year "
                f"FOR VALUES FROM ('{year:04d}-01-01 00:00:00+00') "
                f"TO ('{year + 1:04d}-01-01 00:00:00+00')"
            )
    for table in ("runs", "poses"):
        op.execute(f"CREATE TABLE {table}_default PARTITION OF {table}_by_year DEFAULT")
    op.execute("INSERT INTO runs_by_year SELECT * FROM runs")
    op.execute("INSERT INTO poses_by_year SELECT * FROM poses")
    op.execute("DROP TABLE poses")
    op.execute("DROP TABLE runs")
    for table in ("runs", "poses"):
        op.execute(f"ALTER TABLE {table}_by_year RENAME TO {table}")
        op.execute(f"ALTER TABLE {table} ADD CONSTRAINT pk_{table} PRIMARY KEY (id, started_at)")
    op.execute("ALTER SEQUENCE poses_id_seq OWNED BY poses.id")
    op.execute(
        "ALTER TABLE runs ADD CONSTRAINT fk_runs_id_run_ids FOREIGN KEY (id) "
        "REFERENCES run_ids (run_pk) ON DELETE CASCADE"
    )
    for name, columns in RUN_INDEXES.items():
        op.execute(f"CREATE INDEX {name} ON runs ({columns})")
    _constrain_poses()


def _constrain_poses() -> None:
    """PostgreSQL: the unique key and the reference of a rebuilt ``poses``."""
    op.execute(
        "ALTER TABLE poses ADD CONSTRAINT uq_poses_run_pk_index_started_at "
        "UNIQUE (run_pk, index, started_at)"
    )
    op.execute(
        "ALTER TABLE poses ADD CONSTRAINT fk_poses_run_pk_run_ids FOREIGN KEY (run_pk) "
        "REFERENCES run_ids (run_pk) ON DELETE CASCADE"
    )


def downgrade() -> None:
    if op.get_bind().dialect.name == "postgresql":
        _unpartition()
    else:
        _rebuild_sqlite_runs(REFERENCE_TO_REGISTER, UNIQUE_RUN_ID)
    for table in ("poses", *CHILDREN):
        with op.batch_alter_table(table) as batch:
            batch.drop_constraint(f"fk_{table}_run_pk_run_ids", type_="foreignkey")
            batch.create_foreign_key(
                f"fk_{table}_run_pk_runs", "runs", ["run_pk"], ["id"], ondelete="CASCADE"
            )
    with op.batch_alter_table("poses") as batch:
        batch.drop_constraint("uq_poses_run_pk_index_started_at", type_="unique")
        batch.create_unique_constraint("uq_poses_run_pk_index", ["run_pk", "index"])
        batch.drop_column("started_at")
    op.drop_table("run_ids")


def _unpartition() -> None:
    """PostgreSQL: plain ``runs`` and ``poses`` again, numbered by ``runs_id_seq``."""
    op.execute("ALTER SEQUENCE poses_id_seq OWNED BY NONE")
    for table in ("runs", "poses"):
        op.execute(
            f"CREATE TABLE {table}_plain (LIKE {table} INCLUDING DEFAULTS INCLUDING CONSTRAINTS)"
        )
        op.execute(f"INSERT INTO {table}_plain SELECT * FROM {table}")
    op.execute("DROP TABLE poses")
    op.execute("DROP TABLE runs")
    for table in ("runs", "poses"):
        op.execute(f"ALTER TABLE {table}_plain RENAME TO {table}")
        op.execute(f"ALTER TABLE {table} ADD CONSTRAINT pk_{table} PRIMARY KEY (id)")
    op.execute("ALTER SEQUENCE poses_id_seq OWNED BY poses.id")
    op.execute("ALTER SEQUENCE run_ids_run_pk_seq OWNED BY NONE")
    op.execute("ALTER TABLE run_ids ALTER COLUMN run_pk DROP DEFAULT")
    op.execute("ALTER SEQUENCE run_ids_run_pk_seq RENAME TO runs_id_seq")
    op.execute("ALTER TABLE runs ALTER COLUMN id SET DEFAULT nextval('runs_id_seq')")
    op.execute("ALTER SEQUENCE runs_id_seq OWNED BY runs.id")
    op.execute("ALTER TABLE runs ADD CONSTRAINT uq_runs_run_id UNIQUE (run_id)")
    for name, columns in RUN_INDEXES.items():
        op.execute(f"CREATE INDEX {name} ON runs ({columns})")
    _constrain_poses()
