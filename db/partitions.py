"""Monthly partitions of ``runs`` and ``poses`` on PostgreSQL.

From revision 0025 both tables are partitioned by range of ``started_at``: one partition
a calendar month in UTC (``runs_2027_01``, ``poses_2027_01``), and a default partition
(``runs_default``, ``poses_default``) for any start outside the months created. An insert
then touches the indexes of its month only, vacuum and index upkeep go a month at a time,
and a report over a period reads the months it spans (``docs/api.md``, *Capacity*).

The migration creates the months from the oldest run's to twelve past the current one;
:func:`add_months` (``calstation db partitions``, a monthly job) keeps them ahead, and
gives the runs that went to the default partition (their month had none) a month of
their own, so that no month's rows are split. SQLite keeps plain tables.
"""

import re
from dataclasses import dataclass
from datetime import UTC, datetime

from sqlalchemy import Connection, make_url, text

from db.rollups import lock_submissions
from station.domain.errors import InputError

#: The partitioned tables, ``poses`` holding its run's ``started_at``.
PARTITIONED = ("runs", "poses")
#: How many months past the current one :func:`add_months` keeps, by default.
MONTHS_AHEAD = 12
_PARTITION = re.compile(r"(runs|poses)_(\d{4}_\d{2}|default)")


@dataclass(frozen=True)
class Months:
    """What :func:`add_months` found and did: the first and last month (``YYYY-MM``) the
    tables have (not every month between need have runs), the months it created, and
    the runs it moved out of the default partition."""

    first: str
    last: str
    created: list[str]
    moved: int


def is_partition(name: str) -> bool:
    """Whether ``name`` is one of the partitions, not a table of the models."""
    return _PARTITION.fullmatch(name) is not None


def include_name(name: str | None, type_: str, parent_names: object) -> bool:
    """Alembic's ``include_name``: a partition is part of its table, not a table of the
    models (autogenerate and the models' comparison leave it out)."""
    return not (type_ == "table" and name is not None and is_partition(name))


def _month(index: int) -> str:
    """Month ``index`` (months since year 0) as ``YYYY-MM``."""
    return f"{index // 12:04d}-{index % 12 + 1:02d}"


def _first_moment(index: int) -> datetime:
    """The first moment of month ``index``, in UTC."""
    return datetime(index // 12, index % 12 + 1, 1, tzinfo=UTC)


def require_partitioned(url: str) -> None:
    """:class:`InputError` unless the database at ``url`` is PostgreSQL: SQLite's tables
    are not partitioned."""
    parsed = make_url(url)
    if parsed.get_backend_name() != "postgresql":
        shown = parsed.render_as_string(hide_password=True)
        raise InputError(f"database {shown} is SQLite: only PostgreSQL partitions runs by month")


def add_months(connection: Connection, ahead: int = MONTHS_AHEAD) -> Months:
    """Create the partitions of ``runs`` and ``poses`` missing from the current month to
    ``ahead`` months past it (UTC), and those of every month with runs in the default
    partition, in the caller's transaction.

    Runs land in the default partition when their month has none: a station whose clock
    was wrong, or runs replayed from before the database's first month. Their month is
    created and they, and their poses, move in: the default partition is detached, the
    month created, its rows copied over and deleted, and the default attached again.
    Submissions wait meanwhile (:func:`db.rollups.lock_submissions`). PostgreSQL only
    (:func:`require_partitioned`).
    """
    lock_submissions(connection)
    existing = {
        _index(name)
        for name in connection.scalars(
            text(
                "SELECT c.relname FROM pg_inherits AS i JOIN pg_class AS c ON c.oid = i.inhrelid "
                "WHERE i.inhparent = to_regclass('runs') AND c.relname <> 'runs_default'"
            )
        )
    }
    waiting = connection.scalars(
        text("SELECT DISTINCT to_char(started_at AT TIME ZONE 'UTC', 'YYYY_MM') FROM runs_default")
    )
    now = datetime.now(UTC)
    current = now.year * 12 + now.month - 1
    wanted = {*range(current, current + ahead + 1), *(_index(month) for month in waiting)}
    created = sorted(wanted - existing)
    moved = sum(_create(connection, index) for index in created)
    months = existing | wanted
    return Months(_month(min(months)), _month(max(months)), [_month(i) for i in created], moved)


def _index(name: str) -> int:
    """The month (months since year 0) a name ending in ``YYYY_MM`` stands for."""
    return int(name[-7:-3]) * 12 + int(name[-2:]) - 1


def _create(connection: Connection, index: int) -> int:
    """Create month ``index``'s partitions, moving its rows out of the default ones;
    return how many runs moved."""
    start, end = _first_moment(index), _first_moment(index + 1)
    window = {"start": start, "end": end}
    in_month = "started_at >= :start AND started_at < :end"
    waiting = connection.scalar(text(f"SELECT count(*) FROM runs_default WHERE {in_month}"), window)
    suffix = f"{index // 12:04d}_{index % 12 + 1:02d}"
    for table in PARTITIONED:
        if waiting:
            connection.execute(text(f"ALTER TABLE {table} DETACH PARTITION {table}_default"))
        connection.execute(
            text(
                f"CREATE TABLE {table}_{suffix} PARTITION OF {table} "
                f"FOR VALUES FROM ('{start.isoformat()}') TO ('{end.isoformat()}')"
            )
        )
        if waiting:
            connection.execute(
                text(f"INSERT INTO {table} SELECT * FROM {table}_default WHERE {in_month}"),
                window,
            )
            connection.execute(text(f"DELETE FROM {table}_default WHERE {in_month}"), window)
            connection.execute(
                text(f"ALTER TABLE {table} ATTACH PARTITION {table}_default DEFAULT")
            )
            # The planner's figures of both at once: autovacuum's come a minute or more
            # later, and until then it took the moved rows for an empty month.
            connection.execute(text(f"ANALYZE {table}_{suffix}, {table}_default"))
    return waiting or 0
