"""A parameter split by station, lot, operator, fixture slot, product or software version
(:mod:`station.domain.quality.split`): the latest runs of the range, bounded.

One walk of ``ix_runs_started_at`` backwards over the runs the report's filter selects,
at most :data:`SPLIT_RUNS` of them, reading the parameter and the split's column only;
the groups' figures are computed from that sample (the page says so). The limits are the
report's (:func:`db.report.reports.report_bounds`); over runs of several products, each
product's own, in a section of its own.
"""

from collections import defaultdict

from sqlalchemy import select
from sqlalchemy.orm import Session

from db.models import Run, RunFacts
from db.report.queries import ReportQueries
from db.report.reports import report_bounds
from db.rollups import PER_RUN
from station.domain.quality.figures import ReportFilter
from station.domain.quality.parameters import PARAMETERS
from station.domain.quality.split import NO_VALUE, SplitBy, SplitReport, group_stats

#: The most runs a split reads: the latest of the range.
SPLIT_RUNS = 20_000
#: The most groups a split shows (the largest).
SPLIT_GROUPS = 24
#: The run's column of each split.
SPLIT_COLUMNS = {
    "station": Run.station_id,
    "lot": Run.lot,
    "operator": Run.operator_id,
    "part_number": Run.part_number,
    "fixture_slot": Run.fixture_slot,
    "software_version": Run.software_version,
}
#: The parameters a split reads: one value per run.
SPLIT_PARAMETERS = tuple(spec.name for spec in PARAMETERS if spec.name in PER_RUN)


def split_report(
    session: Session, filter: ReportFilter, parameter: str, by: SplitBy, runs: int = SPLIT_RUNS
) -> SplitReport:
    """``parameter`` (one of :data:`SPLIT_PARAMETERS`) over the latest ``runs`` runs
    ``filter`` selects, split by ``by``; over runs of several products, a section per
    product (its latest ``runs`` runs, against its own limits)."""
    parts = [row.part_number for row in ReportQueries(session, filter).product_counts()]
    if len(parts) < 2:
        return _split(session, filter, parameter, by, runs)
    sections = [
        _split(session, filter.model_copy(update={"part_number": part}), parameter, by, runs)
        for part in parts
    ]
    return SplitReport(
        parameter=parameter,
        unit=sections[0].unit,
        by=by,
        filter=filter,
        lower=None,
        upper=None,
        bounds_source=f"each product against its own limits profile ({len(parts)} products)",
        sampled_runs=sum(s.sampled_runs for s in sections),
        sample_limit=runs,
        groups=[],
        groups_total=sum(s.groups_total for s in sections),
        sections=sections,
    )


def _split(
    session: Session, filter: ReportFilter, parameter: str, by: SplitBy, runs: int
) -> SplitReport:
    """The split of the runs of one product (or none) ``filter`` selects."""
    spec = next(spec for spec in PARAMETERS if spec.name == parameter)
    queries = ReportQueries(session, filter)
    bounds, bounds_source = report_bounds(session, queries.station_counts())
    lower, upper = (None, None) if bounds is None else bounds[spec.family]
    stmt = (
        select(SPLIT_COLUMNS[by].label("group"), PER_RUN[parameter].label("value"))
        .join(RunFacts, RunFacts.run_pk == Run.id)
        .where(*queries.conditions)
        .order_by(Run.started_at.desc(), Run.id.desc())
        .limit(runs)
    )
    rows = session.execute(stmt).all()
    values: dict[str, list[float]] = defaultdict(list)
    for group, value in rows:
        if value is not None:
            values[NO_VALUE if group is None else str(group)].append(float(value))
    largest = sorted(values.items(), key=lambda item: (-len(item[1]), item[0]))[:SPLIT_GROUPS]
    return SplitReport(
        parameter=parameter,
        unit=spec.unit,
        by=by,
        filter=filter,
        lower=lower,
        upper=upper,
        bounds_source=bounds_source,
        sampled_runs=len(rows),
        sample_limit=runs,
        groups=[group_stats(name, v, lower, upper) for name, v in sorted(largest)],
        groups_total=len(values),
        part_number=filter.part_number,
    )
