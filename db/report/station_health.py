"""A station's health page's reads (:mod:`station.domain.quality.station_health`):
bounded, each a walk of ``ix_runs_station_id_started_at`` backwards over the station's runs.

The latest :data:`GOLDEN_CHECKS` golden-unit checks (``runs.purpose`` = ``golden``), the
cycle times (finish less start) of its latest :data:`CYCLE_RUNS` production runs, and the
software versions and limits profiles of those runs.
"""

from sqlalchemy import func, select
from sqlalchemy.orm import Session

from db.models import Run
from db.rollups import PRODUCTION
from db.store.mapping import stored_axes
from station.domain.quality.parameters import COEFFICIENTS
from station.domain.quality.split import group_stats
from station.domain.quality.station_health import StationHealth, VersionUse, golden_checks

#: The most golden checks the page reads (the latest).
GOLDEN_CHECKS = 200
#: The production runs the cycle times and versions come from (the latest).
CYCLE_RUNS = 2000


def station_health(session: Session, station_id: str) -> StationHealth | None:
    """The station's health; ``None`` when no run of it is stored."""
    if session.scalar(select(Run.id).where(Run.station_id == station_id).limit(1)) is None:
        return None
    golden = session.execute(
        select(
            Run.run_id,
            Run.started_at,
            Run.serial,
            Run.verdict,
            *(getattr(Run, c) for c in COEFFICIENTS),
        )
        .where(Run.station_id == station_id, Run.purpose == "golden")
        .order_by(Run.started_at.desc(), Run.id.desc())
        .limit(GOLDEN_CHECKS)
    ).all()
    rows = [
        (
            str(r.run_id),
            r.started_at,
            r.serial,
            r.verdict,
            stored_axes(r, "offset"),
            stored_axes(r, "sensitivity"),
        )
        for r in reversed(golden)
    ]
    checks, drift = golden_checks(rows)
    latest = (
        select(
            Run.started_at,
            Run.finished_at,
            Run.software_version,
            Run.limits_name,
            Run.limits_version,
        )
        .where(Run.station_id == station_id, PRODUCTION)
        .order_by(Run.started_at.desc(), Run.id.desc())
        .limit(CYCLE_RUNS)
        .subquery("latest")
    )
    times = session.execute(select(latest.c.started_at, latest.c.finished_at)).all()
    seconds = [(finished - started).total_seconds() for started, finished in times]
    used = (latest.c.software_version, latest.c.limits_name, latest.c.limits_version)
    versions = session.execute(
        select(
            *used,
            func.count().label("runs"),
            func.min(latest.c.started_at).label("first"),
            func.max(latest.c.started_at).label("last"),
        )
        .group_by(*used)
        .order_by(func.max(latest.c.started_at).desc())
    ).all()
    return StationHealth(
        station_id=station_id,
        golden=checks,
        golden_limit=GOLDEN_CHECKS,
        drift=drift,
        cycle_seconds=group_stats("cycle time", seconds, None, None) if seconds else None,
        cycle_runs=len(seconds),
        versions=[
            VersionUse(
                software_version=v.software_version,
                limits=f"{v.limits_name} v{v.limits_version}",
                runs=v.runs,
                first=v.first,
                last=v.last,
            )
            for v in versions
        ],
    )
