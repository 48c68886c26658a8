"""Yearly partitions of ``runs`` and ``poses`` on PostgreSQL.

From revision 0025 both tables are partitioned by range of ``started_at``: one partition
a calendar year in UTC (``runs_2027``, ``poses_2027``), and a default partition
(``runs_default``, ``poses_default``) for any start outside the years created. An insert
then touches the indexes of its year only, vacuum and index upkeep go a year at a time,
a report over a period reads the years it spans, and retiring a year is detaching its
partitions (``docs/api.md``, *Capacity*).

By year, not by month: a submission looks its unit up by serial number, which no start
prunes, so each of its statements is planned over every partition kept. Measured with
``benchmarks/bench_submit.py``: 11 partitions (ten years) took a submission 1.4–1.8
times its time without partitions, 15 months 2 times, and with 121 (ten years of months)
230 submissions did not finish in 15 minutes (``docs/benchmarks.md``, *partitions*).

The migration creates the years that hold runs, the current one and the next;
:func:`add_years` (``calstation db partitions``, a job run daily or monthly) keeps them
ahead, and gives the runs that went to the default partition (their year had none) a
year of their own, so that no year's rows are split. SQLite keeps plain tables.
"""

import re
from dataclasses import dataclass
from datetime import UTC, datetime

from sqlalchemy import Connection, make_url, text

from db.rollups import lock_submissions
from station.domain.errors import InputError

#: The partitioned tables, ``poses`` holding its run's ``started_at``.
PARTITIONED = ("runs", "poses")
#: How many years past the current one :func:`add_years` keeps, by default.
YEARS_AHEAD = 1
_PARTITION = re.compile(r"(runs|poses)_(\d{4}|default)")


@dataclass(frozen=True)
class Years:
    """What :func:`add_years` found and did: the first and last year the tables have
    (not every year between need have runs), the years it created, and the runs it moved
    out of the default partition."""

    first: int
    last: int
    created: list[int]
    moved: int


def is_partition(name: str) -> bool:
    """Whether ``name`` is one of the partitions, not a table of the models."""
    return _PARTITION.fullmatch(name) is not None


def include_name(name: str | None, type_: str, parent_names: object) -> bool:
    """Alembic's ``include_name``: a partition is part of its table, not a table of the
    models (autogenerate and the models' comparison leave it out)."""
    return not (type_ == "table" and name is not None and is_partition(name))


def require_partitioned(url: str) -> None:
    """:class:`InputError` unless the database at ``url`` is PostgreSQL: SQLite's tables
    are not partitioned."""
    parsed = make_url(url)
    if parsed.get_backend_name() != "postgresql":
        shown = parsed.render_as_string(hide_password=True)
        raise InputError(f"database {shown} is SQLite: only PostgreSQL partitions runs by year")


def add_years(connection: Connection, ahead: int = YEARS_AHEAD) -> Years:
    """Create the partitions of ``runs`` and ``poses`` missing from the current year to
    ``ahead`` years past it (UTC), and those of every year with runs in the default
    partition, in the caller's transaction.

    Runs land in the default partition when their year has none: a station whose clock
    was wrong, or runs replayed from before the database's first year. Their year is
    created and they, and their poses, move in: the default partition is detached, the
    year created, its rows copied over and deleted, the default attached again and both
    analysed. Submissions wait meanwhile (:func:`db.rollups.lock_submissions`).
    PostgreSQL only (:func:`require_partitioned`).
    """
    lock_submissions(connection)
    existing = {
        int(name[-4:])
        for name in connection.scalars(
            text(
                "SELECT c.relname FROM pg_inherits AS i JOIN pg_class AS c ON c.oid = i.inhrelid "
                "WHERE i.inhparent = to_regclass('runs') AND c.relname <> 'runs_default'"
            )
        )
    }
    waiting = connection.scalars(
        text(
            "SELECT DISTINCT CAST(extract(year FROM started_at AT TIME ZONE 'UTC') AS integer) "
            "FROM runs_default"
        )
    )
    current = datetime.now(UTC).year
    wanted = {*range(current, current + ahead + 1), *waiting}
    created = sorted(wanted - existing)
    moved = sum(_create(connection, year) for year in created)
    years = existing | wanted
    return Years(min(years), max(years), created, moved)


def _create(connection: Connection, year: int) -> int:
    """Create ``year``'s partitions, moving its rows out of the default ones; return how
    many runs moved."""
    start, end = (datetime(y, 1, 1, tzinfo=UTC) for y in (year, year + 1))
    window = {"start": start, "end": end}
    in_year = "started_at >= :start AND started_at < :end"
    waiting = connection.scalar(text(f"SELECT count(*) FROM runs_default WHERE {in_year}"), window)
    for table in PARTITIONED:
        if waiting:
            connection.execute(text(f"ALTER TABLE {table} DETACH PARTITION {table}_default"))
        connection.execute(
            text(
                f"CREATE TABLE {table}_{year:04d} PARTITION OF {table} "
                f"FOR VALUES FROM ('{start.isoformat()}') TO ('{end.isoformat()}')"
            )
        )
        if waiting:
            connection.execute(
                text(f"INSERT INTO {table} SELECT * FROM {table}_default WHERE {in_year}"),
                window,
            )
            connection.execute(text(f"DELETE FROM {table}_default WHERE {in_year}"), window)
            connection.execute(
                text(f"ALTER TABLE {table} ATTACH PARTITION {table}_default DEFAULT")
            )
            # The planner's figures of both at once: autovacuum's come a minute or more
            # later, and until then it took the moved rows for an empty year.
            connection.execute(text(f"ANALYZE {table}_{year:04d}, {table}_default"))
    return waiting or 0
