"""The runs of a report's period as rows for a CSV export, read a page at a time.

Keyset pages in start order (``ix_runs_started_at``): each page starts after the last
run of the previous one, so an export of any length holds one page in memory.
"""

from collections.abc import Sequence
from datetime import datetime
from typing import Any

from sqlalchemy import select, tuple_
from sqlalchemy.orm import Session

from db.models import Run, RunFacts
from db.report.queries import conditions
from station.domain.quality.figures import ReportFilter

#: The export's columns, in order: the run's identity (its product too), its verdict and
#: first failure reason, its limits profile, its coefficients, verification error and gyro biases.
COLUMNS: tuple[tuple[str, Any], ...] = (
    ("run_id", Run.run_id),
    ("serial", Run.serial),
    ("started_at", Run.started_at),
    ("finished_at", Run.finished_at),
    ("station_id", Run.station_id),
    ("operator_id", Run.operator_id),
    ("lot", Run.lot),
    ("part_number", Run.part_number),
    ("verdict", Run.verdict),
    ("first_failure", RunFacts.first_failure),
    ("limits_name", Run.limits_name),
    ("limits_version", Run.limits_version),
    ("limits_sha256", Run.limits_sha256),
    *((f"offset_{a}", getattr(Run, f"offset_{a}")) for a in "xyz"),
    *((f"sensitivity_{a}", getattr(Run, f"sensitivity_{a}")) for a in "xyz"),
    ("verification_error_mg", Run.verification_error_mg),
    *((f"gyro_bias_{a}", getattr(RunFacts, f"gyro_bias_{a}")) for a in "xyz"),
)
HEADER = tuple(name for name, _ in COLUMNS)

#: Runs per page of the export.
PAGE = 1000


def run_page(
    session: Session, filter: ReportFilter, after: tuple[datetime, int] | None, size: int = PAGE
) -> tuple[list[Sequence[Any]], tuple[datetime, int] | None]:
    """The next ``size`` runs ``filter`` selects after ``after`` (start, key), oldest
    first, as :data:`HEADER` values; and where the page after them starts (``None``: no
    more)."""
    stmt = (
        select(Run.started_at, Run.id, *(column for _, column in COLUMNS))
        .join(RunFacts, RunFacts.run_pk == Run.id)
        .where(*conditions(filter))
        .order_by(Run.started_at, Run.id)
        .limit(size)
    )
    if after is not None:
        stmt = stmt.where(tuple_(Run.started_at, Run.id) > tuple_(*after))
    rows = session.execute(stmt).all()
    last = (rows[-1].started_at, rows[-1].id) if len(rows) == size else None
    return [tuple(row)[2:] for row in rows], last
