"""What a report process does: the reports' bodies, from the database to the rendered text.

:mod:`api.report_pool` runs these functions in its report processes; the routes of
:mod:`api.routes.reports` hand them their arguments and answer with what they return.
They know nothing of HTTP: a report process imports this module, the database layer and
the renderers, not FastAPI (``tests/api/test_report_pool.py`` pins it): it starts in
about four fifths of the time, and a server's first report comes that much sooner.
"""

from dataclasses import dataclass
from datetime import datetime, time

from db import RunRepository
from db.report import (
    CHART_POINTS,
    SPLIT_PARAMETERS,
    ReportQueries,
    eol_report,
    held_units,
    split_report,
)
from station.domain.i18n import Language
from station.domain.product.limits import LimitsProfile
from station.domain.quality.days import day_end, midnight, plant_date
from station.domain.quality.figures import ReportFilter
from station.domain.quality.split import SplitBy
from station.report.render import render

#: Units on the dashboard's list, and points on each of its control charts.
DASHBOARD_UNITS = 20
DASHBOARD_CHART_POINTS = 60
#: Units on hold the dashboard lists (the latest).
DASHBOARD_HELD = 50
#: Where the dashboard hears of stored runs (:mod:`api.routes.events`).
EVENTS_PATH = "/api/v1/events"
#: The most runs the page of a Pareto bar lists (the latest).
FAILING_RUNS = 200


@dataclass(frozen=True)
class Pages:
    """Which units the list holds: held ones or all, ``size`` of them after ``offset``."""

    held: bool
    size: int
    offset: int
    points: int = CHART_POINTS


@dataclass(frozen=True)
class Plant:
    """The plant's time zone and shift start times, as the report shows its times."""

    zone: str
    shifts: tuple[time, ...]


def eol_body(
    repository: RunRepository,
    filter: ReportFilter,
    pages: Pages,
    format: str,
    plant: Plant,
    candidate: LimitsProfile | None,
    candidate_kept: bool = False,
    language: Language = "en",
) -> str:
    """The end-of-line report rendered as ``format`` (a page in ``language``);
    ``candidate_kept``: the what-if's candidate is stored (a link to it answers it again)."""
    report = eol_report(
        repository.session,
        filter,
        candidate=candidate,
        candidate_kept=candidate_kept,
        unit_limit=pages.size,
        unit_offset=pages.offset,
        held_only=pages.held,
        chart_points=pages.points,
        zone=plant.zone,
        shifts=plant.shifts,
    )
    return render(report, format, language)


def split_body(
    repository: RunRepository,
    filter: ReportFilter,
    parameter: str,
    by: SplitBy,
    format: str,
    zone: str,
    language: Language = "en",
) -> str:
    """A parameter's split by ``by``, as JSON or its page (in ``language``)."""
    report = split_report(repository.session, filter, parameter, by)
    if format == "json":
        return report.model_dump_json(indent=2) + "\n"
    from station.report import html

    return html.split_page(report, zone, SPLIT_PARAMETERS, language)


def failing_runs_body(
    repository: RunRepository,
    filter: ReportFilter,
    code: str,
    zone: str,
    language: Language = "en",
) -> str:
    """The page of a Pareto bar's runs, in ``language``."""
    from station.report import html

    runs = ReportQueries(repository.session, filter).failing_runs(code, FAILING_RUNS)
    return html.failing_runs_page(filter, zone, code, runs, FAILING_RUNS, language)


def dashboard_body(
    repository: RunRepository, now: datetime, zone: str = "UTC", language: Language = "en"
) -> str:
    """The dashboard page at ``now``, in ``language``: the runs of the plant's day (its
    time ``zone``), from its midnight to the next (a run a station's clock dated later is
    no run of today)."""
    today = plant_date(now, zone)
    report = eol_report(
        repository.session,
        ReportFilter(since=midnight(today, zone), until=day_end(today, zone)),
        unit_limit=DASHBOARD_UNITS,
        chart_points=DASHBOARD_CHART_POINTS,
        now=now,
        zone=zone,
        open_holds=False,  # the dashboard lists the units on hold itself
    )
    from station.report import html

    held = held_units(repository.session, DASHBOARD_HELD)
    return html.dashboard_page(
        report, held.units, held.total, events=EVENTS_PATH, language=language
    )
