"""HTML pages: the report, the line dashboard, a unit's page and its certificate.

Jinja2 templates (``templates/``) with autoescaping; charts are inline SVG from
:mod:`station.report.svg`, styles inline: a page needs no other file, no network (the
dashboard's one inline script asks its own server for updates). Every serial on every
page links to the unit's page through one macro, ``serial_link`` in ``base.html``.

Whoever renders a page imports this module where it renders one, never at its own
import: Jinja and the templates' helpers take ~0.1 s to load, which the results
server's start (its API, ``/healthz``) and the report's other formats do not need
(``tests/api/test_start.py``; docs/benchmarks.md, "Server start").
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from datetime import datetime
from typing import Any, Final, get_args
from urllib.parse import urlencode

from jinja2 import Environment, PackageLoader, select_autoescape
from markupsafe import Markup

from station import __version__
from station.domain.i18n import ENGLISH, Language, Say, counter, speaker
from station.domain.product.laboratory import Laboratory
from station.domain.product.limits import LimitsProfile
from station.domain.quality.alerts import Alert
from station.domain.quality.capability import CAPABLE_CPK
from station.domain.quality.days import day_end, midnight
from station.domain.quality.figures import (
    ControlChart,
    EolReport,
    ParameterStats,
    ReportFilter,
    TrendDay,
    TrendFigures,
)
from station.domain.quality.parameters import profile_bounds
from station.domain.quality.split import NO_VALUE, SplitBy, SplitReport
from station.domain.quality.station_health import (
    BASELINE_CHECKS,
    OFFSET_TOLERANCE,
    SENSITIVITY_TOLERANCE,
    StationHealth,
)
from station.domain.record.records import (
    FailureReason,
    GyroFitRecord,
    HoldReview,
    RunSummary,
    StoredRun,
)
from station.domain.record.signature import Signature
from station.domain.record.unit_state import UnitCalibration, deciding_review
from station.report import formatting, svg
from station.report.certificate import (
    as_found,
    as_left,
    check_rows,
    code_words,
    failure_words,
    gyro_as_found,
    gyro_as_left,
    identity,
    influences,
)
from station.report.explanations import explanation
from station.report.gyro_plot import sense_axes_of, svg_g_sensitivity
from station.report.tables import (
    Statistics,
    capability_cells,
    capability_header,
    capability_words,
    listed,
    near_limits_line,
    parameter_cells,
    parameter_header,
    risk_cells,
    risk_header,
    source_words,
    split_name,
    statistics_of,
    summary_cells,
    summary_header,
    what_if_cells,
    what_if_header,
)

_env = Environment(
    loader=PackageLoader("station.report", "templates"),
    autoescape=select_autoescape(["html"]),
    trim_blocks=True,
    lstrip_blocks=True,
)
_env.filters.update(
    percent=formatting.percent,
    number=formatting.number,
    seconds=formatting.seconds,
    # A moment names its zone on every page: the plant's, which each page is given; an
    # alert's evidence (JSON) holds its moments as ISO 8601 text.
    moment=lambda value, zone: formatting.moment(
        datetime.fromisoformat(value) if isinstance(value, str) else value, zone
    ),
    field=formatting.field,
    reason=formatting.reason,
)
_env.globals.update(
    # The page's words: English unless a page is rendered for a reader of another
    # language (:func:`_render`); ``pybabel extract`` reads the templates' calls.
    tr=ENGLISH,
    said=lambda code: code,
    version=__version__,
    histogram=lambda stats, tr=ENGLISH: Markup(svg.histogram(stats, tr)),
    pareto=lambda entries, link=None, tr=ENGLISH: Markup(svg.pareto(entries, link, tr)),
    control_chart=lambda chart, zone="UTC", tr=ENGLISH: Markup(svg.control_chart(chart, zone, tr)),
    box_plots=lambda report, tr=ENGLISH: Markup(svg.box_plots(report, tr)),
)


_env.globals.update(
    summary_header=summary_header,
    summary_cells=summary_cells,
    parameter_header=parameter_header,
    listed=listed,
    what_if_header=what_if_header,
    what_if_cells=what_if_cells,
    capability_header=capability_header,
    capability_cells=capability_cells,
    near_limits_line=near_limits_line,
    risk_header=risk_header,
    risk_cells=risk_cells,
    split_name=split_name,
    source_words=source_words,
    capability_words=capability_words,
)
# The macros of the base template, for every template and every template it includes
# (Jinja's template modules expose their macros as attributes it does not declare).
_base = _env.get_template("base.html").module
_env.globals.update(serial_link=_base.serial_link)  # type: ignore[attr-defined]


def page_words(tr: Say) -> dict[str, str]:
    """The stored codes a page shows as words, in the reader's language: the documents'
    (:func:`station.report.certificate.code_words`) and a unit's disposition and next step."""
    return {
        **code_words(tr),
        "ship": tr("ship"),
        "hold": tr("hold"),
        "scrapped": tr("scrapped"),
        "held": tr("held"),
        "all": tr("all"),
        "open": tr("open"),
        # The ages of open holds (station.domain.quality.figures.HOLD_AGES).
        "< 1 day": tr("< 1 day"),
        "1–7 days": tr("1–7 days"),
        "> 7 days": tr("> 7 days"),
    }


def _render(template: str, language: Language, **context: object) -> str:
    """``template`` rendered for a reader of ``language``: its words (``tr``, ``trn`` for
    a line that names a count), the stored codes it shows (``said``) and failures
    (``failure_text``: rendered from their code and parameters outside English,
    :mod:`station.report.explanations`) in that language; values as the plant formats them."""
    tr = speaker(language)
    words = page_words(tr)

    def failure_text(failure: Any) -> str:
        if language == "en":
            return formatting.reason(failure)
        if not isinstance(failure, FailureReason):  # a row of a query: its fields by name
            failure = FailureReason.model_validate(failure, from_attributes=True)
        return explanation(failure, language)

    return _env.get_template(template).render(
        page_language=language,
        tr=tr,
        trn=counter(language),
        said=lambda code: words.get(code, code),
        failure_text=failure_text,
        **context,
    )


def trend_charts(
    parameters: Sequence[ParameterStats],
    trend: Sequence[TrendFigures],
    periods: Sequence[tuple[str, str]],
    per: str,
    *,
    counts: bool = True,
    tr: Say = ENGLISH,
) -> list[str]:
    """A trend as charts (``per`` "day" or "shift", ``periods`` its axis labels and
    names): (``counts``) units, first-pass and final yield, and the Cpk of each of
    ``parameters`` that has one; titles in the reader's language (``tr``)."""
    daily = per == "day"
    charts = (
        [
            svg.trend_chart(
                tr("units per day (first attempt on the line)")
                if daily
                else tr("units per shift (first attempt on the line)"),
                periods,
                [],
                bars=[d.units for d in trend],
            ),
            svg.trend_chart(
                tr("yield per day") if daily else tr("yield per shift"),
                periods,
                [
                    (tr("first-pass"), [d.first_pass_yield for d in trend]),
                    (tr("final"), [d.final_yield for d in trend]),
                ],
                percent_axis=True,
            ),
        ]
        if counts
        else []
    )
    for p in parameters:
        values = [d.cpk.get(p.name) for d in trend]
        if any(v is not None for v in values):
            charts.append(
                svg.trend_chart(
                    tr("Cpk of {name} per day", name=p.name)
                    if daily
                    else tr("Cpk of {name} per shift", name=p.name),
                    periods,
                    [("Cpk", values)],
                    reference=(tr("target"), CAPABLE_CPK),
                )
            )
    return charts


def day_charts(stats: Statistics, *, counts: bool = True, tr: Say = ENGLISH) -> list[str]:
    """The trend per plant day as charts: the line's, or (not ``counts``) a product
    section's Cpk. The capability a trend of Cpk is read against: AIAG's 1.33 for a
    process in production."""
    days = [(d.day.strftime("%m-%d"), d.day.isoformat()) for d in stats.trend]
    return trend_charts(stats.parameters, stats.trend, days, "day", counts=counts, tr=tr)


def shift_charts(report: EolReport, tr: Say = ENGLISH) -> list[str]:
    """The trend per shift as charts (shifts named by their day and start time): units
    and yields; the Cpk per shift is in the JSON and CSV (sixteen charts of up to 93
    shifts would outweigh the rest of the page)."""
    shifts = [
        (f"{s.day.strftime('%m-%d')} {s.shift}", f"{s.day.isoformat()} {s.shift}")
        for s in report.shift_trend
    ]
    return trend_charts([], report.shift_trend, shifts, "shift", tr=tr)


#: The report (``GET``), and where a what-if is answered again by its profile's SHA-256.
REPORT_PATH = "/api/v1/reports/eol"
#: Where a Pareto bar's runs are listed (:func:`failing_runs_page`).
FAILING_RUNS_PATH = "/api/v1/reports/eol/failures"


#: The CSV export of the runs, and the split page.
RUNS_CSV_PATH = "/api/v1/reports/eol/runs.csv"
SPLIT_PATH = "/api/v1/reports/split"


def filter_fields(filter: ReportFilter, zone: str) -> dict[str, str]:
    """The report's filter as its form's fields, every one (empty: no filter); times in
    the plant's ``zone``."""
    return {
        "from": formatting.field(filter.since, zone),
        "to": formatting.field(filter.until, zone),
        "station": filter.station_id or "",
        "operator": filter.operator_id or "",
        "lot": filter.lot or "",
        "part_number": filter.part_number or "",
    }


def filter_query(filter: ReportFilter, zone: str) -> dict[str, str]:
    """The report's filter as query parameters (empty fields left out). Every link, form
    and export of the pages builds its query from it (:func:`href`), so a filter once
    chosen is kept by all of them."""
    return {name: value for name, value in filter_fields(filter, zone).items() if value}


def href(filter: ReportFilter, zone: str, path: str = REPORT_PATH, **params: object) -> str:
    """The address of ``path`` under ``filter`` with ``params`` besides: a param overrides
    the filter's field of its name, ``None`` leaves it out."""
    query = filter_query(filter, zone)
    for name, value in params.items():
        if value is None:
            query.pop(name, None)
        else:
            query[name] = str(value)
    return f"{path}?{urlencode(query)}"


_env.globals.update(
    href=href, report_path=REPORT_PATH, runs_csv_path=RUNS_CSV_PATH, split_path=SPLIT_PATH
)


def runs_link(filter: ReportFilter, zone: str) -> Callable[[str], str]:
    """The address of the runs behind a Pareto bar (its reason) under ``filter``."""
    return lambda code: href(filter, zone, FAILING_RUNS_PATH, code=code)


def failing_runs_page(
    filter: ReportFilter,
    zone: str,
    code: str,
    runs: Sequence[Any],
    limit: int,
    language: Language = "en",
) -> str:
    """The failing runs whose first failure reason is ``code`` (a Pareto bar's runs),
    the latest ``limit`` of them, times in the plant's ``zone``, in ``language``."""
    return _render(
        "failing_runs.html",
        language,
        filter=filter,
        zone=zone,
        code=code,
        runs=runs,
        limit=limit,
        report_link=href(filter, zone, format="html"),
    )


#: A unit's page (``serial_link`` in ``base.html``).
UNIT_PATH = "/units/"


def _chart_runs(tokens: Sequence[str], span: tuple[float, float], href: str) -> Markup:
    """The attributes that make a block of charts open the runs behind a point: the
    points' ``tokens`` in order (their common start once, as ``data-prefix``), the x of
    the first and last point in the charts' own units, and ``href``, the address with
    ``{0}`` for a point's token; with ``{1}`` too, the tokens are the boundaries of
    contiguous periods (one more than the points), ``{0}`` a period's start and ``{1}``
    its end (the next one's start).

    One list for the block, not a link per point: a report's control charts plot the same
    runs, and a link on each of their points would outweigh the page's 300 kB budget
    (docs/benchmarks.md "report"); the script of ``base.html`` turns a click into the
    address of the nearest point."""
    prefix = ""
    if len(tokens) > 1:  # the common start of all is that of the first and last in order
        low, high = min(tokens), max(tokens)
        same = next(
            (i for i, (a, b) in enumerate(zip(low, high, strict=False)) if a != b), len(low)
        )
        # Each token keeps a character: an empty one would vanish from the list.
        prefix = low[: min(same, min(len(t) for t in tokens) - 1)]
    return Markup(" ").join(
        Markup('data-{}="{}"').format(name, value)
        for name, value in (
            ("runs", " ".join(t[len(prefix) :] for t in tokens)),
            ("prefix", prefix),
            ("x", f"{span[0]:.1f} {span[1]:.1f}"),
            ("href", href),
        )
    )


def control_chart_runs(charts: Sequence[ControlChart]) -> Markup:
    """A control chart's point opens its run's unit page (every chart of ``charts`` plots
    the same runs)."""
    points = charts[0].points if charts else []
    span = (svg.control_x(0, len(points)), svg.control_x(len(points) - 1, len(points)))
    return _chart_runs([p.serial for p in points], span, UNIT_PATH + "{0}")


def trend_runs(
    filter: ReportFilter, zone: str, periods: Sequence[tuple[datetime, datetime]]
) -> Markup:
    """A trend chart's period (a day or a shift, ``periods`` their start and end, each
    ending where the next starts) opens the report of that period, every unit listed: the
    units its points count (their first attempt on the line in the period and the report's
    range, and the rest of its ``filter``)."""
    bounds = [start for start, _ in periods] + [end for _, end in periods[-1:]]
    if bounds and filter.since:
        bounds[0] = max(bounds[0], filter.since)
    if bounds and filter.until:
        bounds[-1] = min(bounds[-1], filter.until)
    # The period's bounds replace the filter's; "{0}" and "{1}" stay as they are.
    rest = filter.model_copy(update={"since": None, "until": None})
    link = href(rest, zone, format="html", list="all")
    span = (svg.trend_x(0, len(periods)), svg.trend_x(len(periods) - 1, len(periods)))
    return _chart_runs([formatting.field(b, zone) for b in bounds], span, link + "&from={0}&to={1}")


def day_runs(filter: ReportFilter, zone: str, trend: Sequence[TrendDay]) -> Markup:
    """A trend per day's day opens the report of that day (:func:`trend_runs`)."""
    days = [(midnight(d.day, zone), day_end(d.day, zone)) for d in trend]
    return trend_runs(filter, zone, days)


def what_if_link(report: EolReport) -> str | None:
    """The address that answers the report's what-if again: its filter and its candidate
    profile by SHA-256 (stored by the what-if)."""
    if report.what_if is None:
        return None
    return href(report.filter, report.timezone, format="html", what_if=report.what_if.limits.sha256)


@dataclass(frozen=True)
class StatisticsBlock:
    """The statistics of one product on the report's page: the report's own when its runs
    are of one product (``part_number`` None), else a product's section, with the cells,
    charts and links the page shows for it."""

    part_number: str | None
    stats: Statistics
    filter: ReportFilter
    parameter_rows: list[list[str]]
    cpk_charts: list[Markup]
    day_runs: Markup
    control_runs: Markup


def statistics_blocks(report: EolReport, tr: Say = ENGLISH) -> list[StatisticsBlock]:
    """The report's statistics as the page shows them: one block over its runs, or one
    per product when they are of several; chart titles in the reader's language (``tr``)."""
    return [
        StatisticsBlock(
            part_number=getattr(stats, "part_number", None),
            stats=stats,
            filter=stats.filter,
            parameter_rows=parameter_cells(stats),
            cpk_charts=(
                [Markup(c) for c in day_charts(stats, counts=False, tr=tr)]
                if report.product_sections
                else []
            ),
            day_runs=day_runs(stats.filter, report.timezone, stats.trend),
            control_runs=control_chart_runs(stats.control_charts),
        )
        for stats in statistics_of(report)
    ]


def report_page(report: EolReport, language: Language = "en") -> str:
    """The end-of-line report as one self-contained HTML page in ``language``."""
    f, zone = report.filter, report.timezone
    tr = speaker(language)
    return _render(
        "report.html",
        language,
        what_if_link=what_if_link(report),
        report=report,
        form={**filter_fields(f, zone), "list": report.units_listed},
        runs_link=runs_link(f, zone),
        page_link=lambda offset: href(
            f,
            zone,
            format="html",
            list=report.units_listed,
            units=report.units_limit,
            page=offset // (report.units_limit or 1) + 1,
        ),
        trend_charts=(
            [Markup(chart) for chart in day_charts(report, tr=tr)] if report.trend else []
        ),
        shift_charts=(
            [Markup(chart) for chart in shift_charts(report, tr)] if report.shift_trend else []
        ),
        day_runs=day_runs(f, zone, report.trend),
        shift_runs=trend_runs(f, zone, [(s.start, s.end) for s in report.shift_trend]),
        blocks=statistics_blocks(report, tr),
    )


def dashboard_page(
    report: EolReport,
    held: Sequence[UnitCalibration],
    held_total: int,
    *,
    events: str,
    language: Language = "en",
) -> str:
    """The line dashboard over ``report`` (today's runs) and the latest ``held`` units on
    hold (of ``held_total``); it follows the server-sent events at ``events`` and brings
    itself up to date after each stored run, without a reload. Its control charts are a
    product's: one set per product when today's runs are of several. In ``language``."""
    return _render(
        "dashboard.html",
        language,
        report=report,
        held=held,
        held_total=held_total,
        events=events,
        runs_link=runs_link(report.filter, report.timezone),
        blocks=statistics_blocks(report, speaker(language)),
    )


def unit_page(
    runs: Sequence[RunSummary],
    generated_at: datetime,
    zone: str = "UTC",
    reviews: Sequence[HoldReview] = (),
    language: Language = "en",
) -> str:
    """A unit's page, in ``language``: its state and every one of its ``runs`` (oldest
    first, at least one), its quality ``reviews`` (oldest first) and, when it is on hold
    and no review has decided since its latest run, the form to review it; times in the
    plant's ``zone``.

    A review after the latest run decides where the unit goes: released for a retest
    (disposition ``retest``, next ``retest``) or scrapped (disposition ``scrapped``,
    nothing next, no form: a scrapped unit is never calibrated again)."""
    unit = UnitCalibration.of_history(runs)
    return _render(
        "unit.html",
        language,
        unit=unit,
        decided=deciding_review(runs, reviews),
        runs=runs,
        reviews=reviews,
        generated_at=generated_at,
        zone=zone,
        document_title=failure_words(speaker(language))[unit.verdict],
    )


def alert_runs_link(alert: Alert, zone: str) -> str:
    """The report of the units behind an alert: every unit from the first of its window
    on (at its station), listed."""
    since = alert.evidence.get("since")
    query = {"format": "html", "list": "all"}
    if isinstance(since, str):
        query["from"] = formatting.field(datetime.fromisoformat(since), zone)
    station = alert.evidence.get("station")
    if isinstance(station, str):
        query["station"] = station
    return f"{REPORT_PATH}?{urlencode(query)}"


def alerts_page(
    alerts: Sequence[Alert], zone: str, rounds: int | None, language: Language = "en"
) -> str:
    """The latest ``alerts``, times in the plant's ``zone``; ``rounds``: the alert loop's
    rounds in this server process (None: no rules configured); in ``language``."""
    return _render(
        "alerts.html",
        language,
        alerts=alerts,
        zone=zone,
        rounds=rounds,
        runs_link=lambda a: alert_runs_link(a, zone),
    )


#: The splits the end-of-line report can be narrowed by, and its query parameter for each.
REPORT_NARROWED_BY: Final[dict[str, str]] = {
    "station": "station",
    "operator": "operator",
    "lot": "lot",
    "part_number": "part_number",
}


def split_page(
    report: SplitReport, zone: str, parameters: Sequence[str], language: Language = "en"
) -> str:
    """A parameter split by a run's column (:mod:`station.domain.quality.split`): box
    plots and each group's figures (a block per product when the runs are of several),
    a form to choose another ``parameters`` or split; in ``language``."""
    narrowing = REPORT_NARROWED_BY.get(report.by)

    def group_link(section: SplitReport, group: str) -> str | None:
        """The report of a group's runs (with every unit listed, of the ``section``'s
        product), where the report can be narrowed to it: a station, operator, lot or
        product, not a slot or a version."""
        if narrowing is None or group == NO_VALUE:
            return None
        return href(section.filter, zone, format="html", list="all", **{narrowing: group})

    return _render(
        "split.html",
        language,
        report=report,
        sections=report.sections or [report],
        zone=zone,
        parameters=parameters,
        splits=get_args(SplitBy),
        form=filter_query(report.filter, zone),
        group_link=group_link,
        no_value=NO_VALUE,
        report_link=href(report.filter, zone, format="html"),
        json_link=href(
            report.filter, zone, SPLIT_PATH, parameter=report.parameter, by=report.by, format="json"
        ),
    )


def station_page(
    health: StationHealth, zone: str, cycle_limit: int, language: Language = "en"
) -> str:
    """A station's health page: golden-unit checks against their baseline (charts and
    table), drift warnings, cycle times (box plot, figures), versions in use; in
    ``language``."""
    tr = speaker(language)
    checks = [c for c in health.golden if c.offset_deviation and c.sensitivity_deviation]
    periods = [
        (formatting.moment(c.started_at, zone)[5:16], formatting.moment(c.started_at, zone))
        for c in checks
    ]
    golden_charts = []
    for name, tolerance, attribute in (
        (tr("offset Δ from baseline (counts)"), OFFSET_TOLERANCE, "offset_deviation"),
        (
            tr("sensitivity Δ from baseline (counts/g)"),
            SENSITIVITY_TOLERANCE,
            "sensitivity_deviation",
        ),
    ):
        series = [
            (axis, [getattr(c, attribute)[i] for c in checks]) for i, axis in enumerate("xyz")
        ]
        chart = svg.trend_chart(name, periods, series, reference=(tr("tolerance"), tolerance))
        golden_charts.append(Markup(chart))
    cycle_chart = None
    if health.cycle_seconds is not None:
        cycle = SplitReport(
            parameter=tr("cycle time"),
            unit="s",
            by="station",
            filter=ReportFilter(station_id=health.station_id),
            lower=None,
            upper=None,
            bounds_source="no limits",
            sampled_runs=health.cycle_runs,
            sample_limit=cycle_limit,
            groups=[health.cycle_seconds.model_copy(update={"group": health.station_id})],
            groups_total=1,
        )
        cycle_chart = Markup(svg.box_plots(cycle, tr))
    return _render(
        "station.html",
        language,
        health=health,
        zone=zone,
        golden_charts=golden_charts if checks else [],
        cycle_chart=cycle_chart,
        cycle_limit=cycle_limit,
        baseline=BASELINE_CHECKS,
        offset_tolerance=OFFSET_TOLERANCE,
        sensitivity_tolerance=SENSITIVITY_TOLERANCE,
    )


def problem_page(
    title: str, message: str, form: dict[str, str] | None = None, language: Language = "en"
) -> str:
    """The page of a request a page could not answer: ``message``, one line, says why;
    ``form``: the report's filter fields as they were sent, to correct them. The page's
    ``title`` (a route's, in English) and its words in ``language``; ``message`` as
    the check that refused it says it."""
    tr = speaker(language)
    titles = {
        "End-of-line report": tr("End-of-line report"),
        "Analysis by split": tr("Analysis by split"),
        "Failing runs": tr("Failing runs"),
        "Review of a unit on hold": tr("Review of a unit on hold"),
        "Find a unit": tr("Find a unit"),
    }
    title = titles.get(title, title)
    return _render("problem.html", language, title=title, message=message, form=form)


def found_page(prefix: str, serials: Sequence[str], more: bool, language: Language = "en") -> str:
    """The units whose serial begins with ``prefix`` (``more``: the list is cut)."""
    return _render("found.html", language, prefix=prefix, serials=serials, more=more)


def not_found_page(message: str, language: Language = "en") -> str:
    """The page of a name nothing is stored under: ``message`` says which."""
    return _render("not_found.html", language, message=message)


def unknown_unit_page(serial: str, language: Language = "en") -> str:
    """The page of a serial number no run is stored under."""
    tr = speaker(language)
    message = tr("No calibration run of serial {serial} is stored.", serial=serial)
    return not_found_page(message, language)


def unknown_station_page(station_id: str, language: Language = "en") -> str:
    """The page of a station no run is stored of."""
    tr = speaker(language)
    message = tr("No calibration run of station {station} is stored.", station=station_id)
    return not_found_page(message, language)


def no_serial_page(title: str, prefix: str, language: Language = "en") -> str:
    """The search's page when no unit's serial number begins with ``prefix``."""
    tr = speaker(language)
    message = tr("No unit's serial number begins with {prefix}.", prefix=prefix)
    return problem_page(title, message, language=language)


def certificate_page(
    run: StoredRun,
    profile: LimitsProfile | None,
    issued_at: datetime,
    gyro_fit: GyroFitRecord | None = None,
    earlier: Sequence[RunSummary] = (),
    zone: str = "UTC",
    golden: RunSummary | None = None,
    reviews: Sequence[HoldReview] = (),
    language: Language = "en",
    laboratory: Laboratory | None = None,
    signature: Signature | None = None,
) -> str:
    """The calibration certificate of the unit whose latest run is ``run``, or its failure
    report when that run failed (what failed, the values and their limits): a unit on hold
    gets no certificate. ``earlier``: the unit's runs before ``run``, listed too.
    ``language``: the reader's; every word of the page is in it, the failures (this
    run's and the earlier runs') rendered from their code and parameters
    (:mod:`station.report.explanations`); codes, serials and values as stored.

    ``profile`` is the run's limits profile as the results database stores it, shown
    next to the coefficients; ``None`` when the run's station never sent it (older
    stations), which the page says. Times are in the plant's ``zone``, as on the unit's page.
    ``reviews``: the unit's quality reviews (a failure report lists them).
    ``gyro_fit``, the unit's latest gyro fit, adds its coefficients and, when its
    dwells were kept, the scale-factor error plot before and after compensation.
    ``golden``: that shift's golden-unit check at the run's station, its reference
    (ISO/IEC 17025 7.8; the identity block, :func:`station.report.certificate.identity`).
    ``laboratory``: who issues it, where, for whom, and the reference's traceability
    (configured; none: "not configured"). The coefficients as found and as left
    (:func:`station.report.certificate.as_found`) follow the results. ``signature``:
    the authorised signatory's (:mod:`station.domain.record.signature`), named with the links
    that verify it; None: the page says it is not signed.
    """
    plot = None
    if gyro_fit is not None and gyro_fit.dwells is not None and not gyro_fit.report.unestimable:
        model = gyro_fit.report.error_model()
        plot = svg_g_sensitivity(
            gyro_fit.dwells.to_log(), model, sense_axes_of(gyro_fit.report, model)
        )
    tr = speaker(language)
    words = failure_words(tr)
    codes = code_words(tr)
    return _env.get_template("certificate.html").render(
        run=run,
        profile=profile,
        bounds=None if profile is None else profile_bounds(profile),
        issued_at=issued_at,
        gyro_fit=gyro_fit,
        earlier=earlier,
        zone=zone,
        reviews=reviews,
        document_title=words[run.verdict],
        words=words,
        page_language=language,
        tr=tr,
        said=lambda code: codes.get(code, code),
        explain=lambda failure: explanation(failure, language),
        failure_text=lambda failure: (
            formatting.reason(failure) if language == "en" else explanation(failure, language)
        ),
        gyro_plot=Markup(plot) if plot is not None else None,
        identity=identity(run, golden, tr, laboratory=laboratory, issued_at=issued_at),
        checks=None if profile is None else check_rows(run, profile, tr),
        influences=influences(run, tr),
        found=as_found(run),
        left=as_left(run),
        gyro_found=gyro_as_found(run),
        gyro_left=gyro_as_left(run),
        signature=signature,
    )
