"""The end-of-line report's queries over what :mod:`db.store` stores and the roll-ups of
:mod:`db.rollups`: the report (``eol_report``), its charts, trends, split and what-if,
open holds, station health, alerts and the runs export.
"""

from db.report.alerts import claim_next, evaluate, mark_delivered, recent_alerts, retry_later
from db.report.chart_queries import first_moving_ranges, latest_chart_points
from db.report.holds import held_units
from db.report.queries import ReportQueries
from db.report.reports import CHART_POINTS, eol_report
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
