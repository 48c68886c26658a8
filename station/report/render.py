"""The report in every format: text for the terminal, CSV, JSON, HTML.

CSV is the report flattened into ``section, item, metric, value`` rows (one value per
row, numbers as JSON writes them), so a spreadsheet or a script reads the same numbers
the JSON holds. Text and HTML format numbers through :mod:`station.report.formatting`.
"""

import csv
import functools
import io
import json
from collections.abc import Iterator, Mapping, Sequence
from typing import Any

from station.domain.i18n import Language
from station.domain.quality.figures import EolReport, TrendFigures
from station.report.formatting import moment, number, percent
from station.report.tables import (
    Statistics,
    capability_cells,
    capability_header,
    flip_cells,
    flip_header,
    listed,
    near_limits_line,
    parameter_cells,
    parameter_header,
    risk_cells,
    risk_header,
    statistics_of,
    summary_cells,
    summary_header,
    what_if_cells,
    what_if_header,
)

MEDIA_TYPES: dict[str, str] = {
    "text": "text/plain; charset=utf-8",
    "csv": "text/csv; charset=utf-8",
    "json": "application/json",
    "html": "text/html; charset=utf-8",
}

Cell = str | int | float | None


def as_json(report: EolReport) -> str:
    """The report as a JSON document."""
    return json.dumps(report.model_dump(mode="json"), indent=2, allow_nan=False) + "\n"


def _trend_rows(
    section: str, item: str, period: Mapping[str, Any], named: set[str]
) -> Iterator[tuple[str, str, str, Cell]]:
    """One period of a trend as rows: its figures and each parameter's Cpk."""
    for key, value in period.items():
        if key == "cpk":
            for name, cpk in value.items():
                yield (section, item, f"cpk:{name}", cpk)
        elif key not in named:
            yield (section, item, key, value)


def _trend_table(per: str, names: Sequence[str], trend: Sequence[TrendFigures]) -> list[str]:
    """A trend as a text table, a line per period."""
    return _table(
        [per, "units", "first-pass yield", "final yield", "runs", "run yield"],
        [
            [
                name,
                number(d.units),
                percent(d.first_pass_yield),
                percent(d.final_yield),
                number(d.runs),
                percent(d.run_yield),
            ]
            for name, d in zip(names, trend, strict=True)
        ],
    )


def _statistics_rows(doc: Mapping[str, Any], prefix: str) -> Iterator[tuple[str, str, str, Cell]]:
    """The rows of a set of statistics of coefficients (the report's, or a product
    section's, each item after ``prefix``: the part number and a slash)."""
    for stats in doc["parameters"]:
        for key, value in stats.items():
            if key not in ("name", "histogram"):
                yield ("parameter", f"{prefix}{stats['name']}", key, value)
        hist = stats["histogram"]
        yield ("histogram", f"{prefix}{stats['name']}", "start", hist["start"])
        yield ("histogram", f"{prefix}{stats['name']}", "width", hist["width"])
        for i, count in enumerate(hist["counts"]):
            yield ("histogram", f"{prefix}{stats['name']}", f"bin:{i}", count)
    for chart in doc["control_charts"]:
        for key, value in chart.items():
            if key not in ("name", "points"):
                yield ("control_chart", f"{prefix}{chart['name']}", key, value)
        for point in chart["points"]:
            yield (
                "control_point",
                f"{prefix}{chart['name']}",
                f"{point['started_at']} {point['serial']}",
                point["value"],
            )
    near = doc.get("near_limits")
    if near is not None:
        for key, value in near.items():
            if key != "risks":
                yield ("near_limits", prefix.rstrip("/"), key, value)
        for risk in near["risks"]:
            for key, value in risk.items():
                if key != "name":
                    yield ("near_limits", f"{prefix}risk:{risk['name']}", key, value)


def rows(report: EolReport) -> Iterator[tuple[str, str, str, Cell]]:
    """The report as ``(section, item, metric, value)`` rows."""
    doc = report.model_dump(mode="json")
    yield ("report", "", "generated_at", doc["generated_at"])
    for key, value in doc["filter"].items():
        yield ("filter", "", key, value)
    yield ("limits", "", "bounds_source", doc["bounds_source"])
    for ref in doc["limits_profiles"]:
        yield ("limits", f"{ref['name']}@{ref['version']}", "sha256", ref["sha256"])
    for key, value in doc["summary"].items():
        yield ("summary", "", key, value)
    for station in doc["stations"]:
        for key, value in station["summary"].items():
            yield ("station", station["station_id"], key, value)
    for product in doc["products"]:
        for key, value in product["summary"].items():
            yield ("product", product["part_number"], key, value)
    yield ("trend", "", "timezone", doc["timezone"])
    for day in doc["trend"]:
        yield from _trend_rows("trend", day["day"], day, {"day"})
    for shift in doc["shift_trend"]:
        item = f"{shift['day']} {shift['shift']}"
        yield from _trend_rows("shift_trend", item, shift, {"day", "shift"})
    for entry in doc["pareto"]:
        for key in ("count", "share", "cumulative_share"):
            yield ("pareto", entry["code"], key, entry[key])
        for station, n in entry["by_station"].items():
            yield ("pareto", entry["code"], f"station:{station}", n)
        for operator, n in entry["by_operator"].items():
            yield ("pareto", entry["code"], f"operator:{operator}", n)
    yield from _statistics_rows(doc, "")
    what_if = doc["what_if"]
    if what_if is not None:
        for key, value in what_if["limits"].items():
            yield ("what_if", "limits", key, value)
        for key in ("pass_to_fail", "fail_to_pass", "flips_total"):
            yield ("what_if", "", key, what_if[key])
        for flip in what_if["flips"]:
            for key in ("before", "after", "check"):
                yield ("what_if", f"flip:{flip['serial']}", key, flip[key])
        for key, value in what_if["summary"].items():
            yield ("what_if", "summary", key, value)
        for entry in what_if["pareto"]:
            for key in ("count", "share", "cumulative_share"):
                yield ("what_if", f"pareto:{entry['code']}", key, entry[key])
        for stats in what_if["parameters"]:
            for key in ("lower", "upper", "count", "cp", "cpk", "out_of_limits", "marginal"):
                yield ("what_if", f"parameter:{stats['name']}", key, stats[key])
    for section in doc["product_sections"]:
        part = section["part_number"]
        yield ("product_section", part, "bounds_source", section["bounds_source"])
        for ref in section["limits_profiles"]:
            yield ("product_section", part, f"limits:{ref['name']}@{ref['version']}", ref["sha256"])
        for day in section["trend"]:
            for name, cpk in day["cpk"].items():
                yield ("trend", f"{part}/{day['day']}", f"cpk:{name}", cpk)
        yield from _statistics_rows(section, f"{part}/")
    holds = doc["open_holds"]
    if holds is not None:
        yield ("open_holds", "", "total", holds["total"])
        for part in ("by_age", "by_cause"):
            for count in holds[part]:
                yield ("open_holds", part, count["label"], count["units"])
    yield ("units", "", "total", doc["units_total"])
    yield ("units", "", "listed", doc["units_listed"])
    yield ("units", "", "held", doc["units_held"])
    yield ("units", "", "offset", doc["units_offset"])
    for unit in doc["units"]:
        for key, value in unit.items():
            if key != "serial":
                yield ("unit", unit["serial"], key, value)


def as_csv(report: EolReport) -> str:
    """The report as CSV rows ``section,item,metric,value``."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["section", "item", "metric", "value"])
    writer.writerows(rows(report))
    return buffer.getvalue()


def _table(header: list[str], body: list[list[str]]) -> list[str]:
    widths = [max(len(row[i]) for row in [header, *body]) for i in range(len(header))]

    def line(row: list[str]) -> str:
        first = row[0].ljust(widths[0])
        rest = (cell.rjust(width) for cell, width in zip(row[1:], widths[1:], strict=True))
        return "  ".join([first, *rest]).rstrip()

    return [line(header), line(["-" * w for w in widths]), *(line(row) for row in body)]


def as_text(report: EolReport) -> str:
    """The report for a terminal: tables of plain text."""
    f = report.filter
    scope = ", ".join(
        f"{label} {value}"
        for label, value in (
            ("from", moment(f.since, report.timezone) if f.since else None),
            ("to", moment(f.until, report.timezone) if f.until else None),
            ("station", f.station_id),
            ("operator", f.operator_id),
            ("lot", f.lot),
            ("product", f.part_number),
        )
        if value
    )
    out = [
        f"End-of-line report ({scope or 'all runs'}), "
        f"generated {moment(report.generated_at, report.timezone)}",
        "",
        *_table(
            summary_header(),
            [
                summary_cells("all", report.summary),
                *(summary_cells(s.station_id, s.summary) for s in report.stations),
            ],
        ),
        "",
        "Per product (part number)",
        *_table(
            ["part number", *summary_header()[1:]],
            [summary_cells(p.part_number, p.summary) for p in report.products],
        ),
        "",
        f"Trend per day ({report.timezone}; units counted on the day of their first attempt)",
        *_trend_table("day", [d.day.isoformat() for d in report.trend], report.trend),
        *(
            [
                "",
                f"Trend per shift ({report.timezone}; shifts start at "
                f"{', '.join(report.shifts)} and belong to the day they start on)",
                *_trend_table(
                    "shift",
                    [f"{s.day.isoformat()} {s.shift}" for s in report.shift_trend],
                    report.shift_trend,
                ),
            ]
            if report.shift_trend
            else []
        ),
        "",
        "Failure Pareto (first failure reason of each failing run)",
        *_table(
            ["reason", "runs", "share", "cumulative", "stations", "operators"],
            [
                [
                    e.code,
                    number(e.count),
                    percent(e.share),
                    percent(e.cumulative_share),
                    " ".join(f"{k}:{v}" for k, v in e.by_station.items()),
                    " ".join(f"{k}:{v}" for k, v in e.by_operator.items()),
                ]
                for e in report.pareto
            ],
        ),
        "",
        *(line for stats in statistics_of(report) for line in _statistics_text(stats)),
        *_what_if_text(report),
        f"Units ({listed(report)}, newest first run first)",
        *_table(
            ["serial", "disposition", "runs", "last run", "station", "operator", "failure"],
            [
                [
                    u.serial,
                    u.disposition,
                    number(u.runs),
                    moment(u.last_started_at, report.timezone),
                    u.station_id,
                    u.operator_id,
                    u.failure or "",
                ]
                for u in report.units
            ],
        ),
    ]
    return "\n".join(out) + "\n"


def _statistics_text(stats: Statistics) -> list[str]:
    """A set of statistics of coefficients as text: the report's, or a product section's
    (its part number named)."""
    part = getattr(stats, "part_number", None)
    of = f" of product {part}" if part else ""
    return [
        f"Parameters{of} against {stats.bounds_source}",
        *_table(parameter_header(), parameter_cells(stats)),
        *([near_limits_line(stats)] if stats.near_limits is not None else []),
        *(
            _table(risk_header(), risk_cells(stats))
            if stats.near_limits is not None and stats.near_limits.risks
            else []
        ),
        "",
        f"Control charts{of} (I-MR, limits from every run in range)",
        *_table(
            ["coefficient", "n", "mean", "MR-bar", "LCL", "UCL", "MR UCL"],
            [
                [
                    c.name,
                    number(c.count),
                    number(c.mean),
                    number(c.mr_bar),
                    number(c.lcl),
                    number(c.ucl),
                    number(c.mr_ucl),
                ]
                for c in stats.control_charts
            ],
        ),
        "",
    ]


def _what_if_text(report: EolReport) -> list[str]:
    """The what-if section: yields, Pareto and capability under the candidate."""
    w = report.what_if
    if w is None:
        return []
    ref = w.limits
    return [
        f"What-if: the runs re-judged against {ref.name} v{ref.version} ({ref.sha256[:12]}); "
        "nothing stored changed",
        *_table(what_if_header(), what_if_cells(report)),
        "",
        *_table(
            ["reason (what-if)", "runs", "share", "cumulative"],
            [
                [e.code, number(e.count), percent(e.share), percent(e.cumulative_share)]
                for e in w.pareto
            ],
        ),
        "",
        *_table(capability_header(), capability_cells(report)),
        "",
        f"Units whose verdict would flip: {w.flips_total}",
        *_table(flip_header(), flip_cells(report)),
        "",
    ]


def as_html(report: EolReport, language: Language = "en") -> str:
    """The report as a page in ``language`` (:mod:`station.report.html`, imported for it
    only)."""
    from station.report import html

    return html.report_page(report, language)


def render(report: EolReport, format: str, language: Language = "en") -> str:
    """The report in ``format`` (one of :data:`station.domain.constants.FORMATS`); a page
    in ``language`` (the other formats are the plant's records, in English)."""
    renderers: dict[str, Any] = {
        "text": as_text,
        "csv": as_csv,
        "json": as_json,
        "html": functools.partial(as_html, language=language),
    }
    text: str = renderers[format](report)
    return text
