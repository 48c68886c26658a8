"""The end-of-line report's queries over the store's tables and the roll-ups of
:mod:`db.rollups`: the report's sections, control charts, trends, split, what-if,
open holds, station health, alerts and the runs export.

Public surface::

    eol_report(session, filter, ...)    the whole report (reports.py)
    ReportQueries(session, filter)      one SQL statement per section
    split_report / station_health       the split page, a station's health
    held_units                          the dashboard's units on hold
    evaluate / claim_next / ...         the alert rules' loop (alerts.py)
    run_page                            the runs export, a page at a time
"""

from db.report.alerts import claim_next, evaluate, mark_delivered, recent_alerts, retry_later
from db.report.chart_queries import first_moving_ranges, latest_chart_points
from db.report.holds import held_units
from db.report.reports import CHART_POINTS, ReportQueries, eol_report
from db.report.run_export import HEADER, PAGE, run_page
from db.report.split import SPLIT_PARAMETERS, SPLIT_RUNS, split_report
from db.report.station_health import CYCLE_RUNS, station_health

__all__ = [
    "CHART_POINTS",
    "CYCLE_RUNS",
    "HEADER",
    "PAGE",
    "SPLIT_PARAMETERS",
    "SPLIT_RUNS",
    "ReportQueries",
    "claim_next",
    "eol_report",
    "evaluate",
    "first_moving_ranges",
    "held_units",
    "latest_chart_points",
    "mark_delivered",
    "recent_alerts",
    "retry_later",
    "run_page",
    "split_report",
    "station_health",
]
