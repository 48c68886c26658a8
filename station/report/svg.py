"""Charts as inline SVG, drawn on the server: histograms with limit lines, the failure
Pareto, individuals and moving-range (I-MR) control charts. No script, no external file.
"""

import math
from collections.abc import Callable, Sequence
from xml.sax.saxutils import escape

from station.domain.i18n import ENGLISH, Say
from station.domain.quality.figures import ChartPoint, ControlChart, ParameterStats, ParetoEntry
from station.domain.quality.split import SplitReport
from station.report.formatting import clock, number, percent
from station.report.tables import split_name

WIDTH, HEIGHT, PAD = 360, 150, 28
LIMIT_COLOUR, CENTRE_COLOUR, BAR_COLOUR, ALARM_COLOUR = "#c0392b", "#2c7a2c", "#3b6ea5", "#c0392b"
AXIS_COLOUR = "#999"
#: Drawn under a label's letters, so a line through it does not hide them.
HALO = 'paint-order="stroke" stroke="#fff" stroke-width="3" stroke-linejoin="round"'
#: The control chart's size: room on the left for the time axis' first label, on the
#: right for the values of the centre and limit lines.
CHART_WIDTH, CHART_LEFT, CHART_RIGHT, PANEL = 480, 36, 84, 130
#: Least distance between two labels of lines, one above the other.
LABEL_GAP = 10


def _svg(title: str, body: Sequence[str], height: float = HEIGHT, width: float = WIDTH) -> str:
    return (
        f'<svg class="chart" role="img" xmlns="http://www.w3.org/2000/svg" '
        f'viewBox="0 0 {width} {height}" width="{width}" height="{height}">'
        f"<title>{escape(title)}</title>{''.join(body)}</svg>"
    )


#: How wide a character of a label is drawn, at most (px, 9 px type): a time axis label
#: near an edge is anchored at it, so the chart does not cut it.
CHAR_WIDTH = 5.5


def _tick_label(x: float, y: float, label: str, width: float) -> str:
    """A time axis' label under its tick at ``x``, centred unless that would cut it at
    the chart's left or right edge (``width``): then it ends, or starts, at its tick."""
    half = CHAR_WIDTH * len(label) / 2
    anchor = "end" if x + half > width - 1 else "start" if x - half < 1 else "middle"
    return _text(x, y, label, anchor)


def _text(x: float, y: float, label: str, anchor: str = "start", colour: str = "#333") -> str:
    return (
        f'<text x="{x:.1f}" y="{y:.1f}" font-size="9" fill="{colour}" '
        f'text-anchor="{anchor}">{escape(label)}</text>'
    )


def _line(x1: float, y1: float, x2: float, y2: float, colour: str, dash: bool = False) -> str:
    pattern = ' stroke-dasharray="4 3"' if dash else ""
    return (
        f'<line x1="{x1:.1f}" y1="{y1:.1f}" x2="{x2:.1f}" y2="{y2:.1f}" '
        f'stroke="{colour}" stroke-width="1"{pattern}/>'
    )


def histogram(stats: ParameterStats, tr: Say = ENGLISH) -> str:
    """The parameter's values (the latest runs', :attr:`ParameterStats.distribution`) in
    bins from the data, on a count axis, with the mean and the limits: the limits join
    the value axis unless they would squeeze the values into less than a third of it,
    else an arrow at the edge names them. Words in the reader's language (``tr``)."""
    d = stats.distribution
    title = tr("histogram of {name}", name=stats.name)
    if d is None or not d.counts:
        return _svg(
            title,
            [_text(WIDTH / 2, HEIGHT / 2, tr("{name}: no values", name=stats.name), "middle")],
        )
    low, high = d.edges[0], d.edges[-1]
    for limit in (stats.lower, stats.upper):
        if limit is not None:
            wider = (min(low, limit), max(high, limit))
            if 3 * (high - low) >= wider[1] - wider[0]:
                low, high = wider
    margin = (high - low) * 0.03
    low, high = low - margin, high + margin
    left, right, top, bottom = 34, WIDTH - 10, PAD, HEIGHT - PAD
    most = max(d.counts) or 1

    def x_of(value: float) -> float:
        return left + (right - left) * (value - low) / (high - low)

    def y_of(count: float) -> float:
        return bottom - (bottom - top) * count / most

    body = [
        _line(left, bottom, right, bottom, AXIS_COLOUR),
        _line(left, top, left, bottom, AXIS_COLOUR),
        _text(left - 3, top + 3, str(most), "end"),
        _text(left - 3, bottom + 3, "0", "end"),
        _text(left - 3, (top + bottom) / 2 + 3, tr("count"), "end"),
    ]
    # Size (the report page's 300 kB target, docs/benchmarks.md): the bars are one path
    # of whole-pixel boxes, not an element each.
    boxes = []
    for i, count in enumerate(d.counts):
        if count:
            x0, x1 = x_of(d.edges[i]), x_of(d.edges[i + 1])
            width = max(round(x1 - x0) - 1, 1)
            boxes.append(f"M{x0:.0f} {bottom:.0f}V{y_of(count):.0f}h{width}V{bottom:.0f}z")
    body.append(f'<path class="bars" fill="{BAR_COLOUR}" d="{"".join(boxes)}"/>')
    if d.mean is not None:
        x = x_of(d.mean)
        body.append(_line(x, top - 2, x, bottom, CENTRE_COLOUR, dash=True))
        body.append(_text(x, top - 4, f"x̄ {number(d.mean)}", "middle", CENTRE_COLOUR))
    for label, limit, edge, arrow in (
        ("LSL", stats.lower, left, "← "),
        ("USL", stats.upper, right, ""),
    ):
        if limit is None:
            continue
        if low <= limit <= high:
            x = x_of(limit)
            body.append(_line(x, top - 12, x, bottom, LIMIT_COLOUR))
            anchor = "start" if x < left + 40 else "end" if x > right - 40 else "middle"
            body.append(_text(x, top - 14, f"{label} {number(limit)}", anchor, LIMIT_COLOUR))
        else:  # beyond the axis: named at its edge
            text = f"{arrow}{label} {number(limit)}{'' if arrow else ' →'}"
            anchor = "start" if arrow else "end"
            body.append(_text(edge, top - 14, text, anchor, LIMIT_COLOUR))
    for apart, x, anchor, words in (
        (d.below, left + 2, "start", "← " + tr("{count} below", count=d.below)),
        (d.above, right - 2, "end", tr("{count} above", count=d.above) + " →"),
    ):
        if apart:  # far-out values, counted apart (Tukey's fences)
            body.append(_text(x, (top + bottom) / 2, words, anchor, ALARM_COLOUR))
    body.append(_text(left, HEIGHT - 8, number(low)))
    body.append(_text(right, HEIGHT - 8, number(high), "end"))
    sample = (
        tr(", latest {values} of {count}", values=d.values, count=stats.count)
        if d.values < stats.count
        else ""
    )
    body.append(
        _text((left + right) / 2, HEIGHT - 8, f"{stats.name} ({stats.unit}){sample}", "middle")
    )
    return _svg(title, body)


def pareto(
    entries: Sequence[ParetoEntry],
    link: Callable[[str], str] | None = None,
    tr: Say = ENGLISH,
) -> str:
    """Failing runs per first failure reason, largest first: each bar labelled with its
    count and its own share; the cumulative share a line against the top axis (0–100 %).
    ``link``: the address of a reason's runs, each bar and its label a link there."""
    rows = list(entries)[:10]
    row_h, top_h, width = 18, 22, CHART_WIDTH
    height = max(len(rows), 1) * row_h + top_h + 8
    label_w = 150
    plot_w = width - label_w - 96  # room right of the plot for the counts
    top = max((e.count for e in rows), default=1)
    body = [_line(label_w, top_h, label_w + plot_w, top_h, AXIS_COLOUR)]
    for share, anchor in ((0.0, "start"), (0.5, "middle"), (1.0, "end")):
        x = label_w + plot_w * share
        body.append(_line(x, top_h - 3, x, top_h, AXIS_COLOUR))
        body.append(_text(x, top_h - 6, percent(share), anchor, CENTRE_COLOUR))
    body.append(_text(label_w - 6, top_h - 6, tr("cumulative share"), "end", CENTRE_COLOUR))
    cumulative = []
    for i, entry in enumerate(rows):
        y = top_h + 4 + i * row_h
        bar = plot_w * entry.count / top
        bar_body = _text(label_w - 4, y + 12, entry.code[:28], "end") + (
            f'<rect class="bar" x="{label_w}" y="{y + 2}" width="{max(bar, 1):.1f}" '
            f'height="{row_h - 4}" fill="{BAR_COLOUR}"><title>{entry.count}</title></rect>'
        )
        if link is not None:
            href = escape(link(entry.code), {'"': "&quot;"})
            bar_body = f'<a class="runs" href="{href}">{bar_body}</a>'
        body.append(bar_body)
        # The counts in a column right of the plot: the cumulative line, which may reach
        # across the plot, never crosses them.
        body.append(_text(label_w + plot_w + 6, y + 12, f"{entry.count} ({percent(entry.share)})"))
        cumulative.append((label_w + plot_w * entry.cumulative_share, y + row_h / 2))
    if cumulative:
        path = " ".join(f"{x:.1f},{y:.1f}" for x, y in cumulative)
        body.append(
            f'<polyline class="cumulative" points="{path}" fill="none" stroke="{CENTRE_COLOUR}"/>'
        )
        body += [
            f'<circle cx="{x:.1f}" cy="{y:.1f}" r="2" fill="{CENTRE_COLOUR}"/>'
            for x, y in cumulative
        ]
    else:
        body.append(_text(width / 2, top_h + 16, tr("no failures"), "middle"))
    return _svg(tr("failure Pareto: runs per first failure reason"), body, height, width)


def _time_axis(
    points: Sequence[ChartPoint], x_of: Callable[[int], float], y: float, zone: str
) -> list[str]:
    """The run-order axis along ``y`` with the start time of four runs as ticks."""
    body = [_line(CHART_LEFT, y, CHART_WIDTH - CHART_RIGHT, y, AXIS_COLOUR)]
    ticks = sorted({round(k * (len(points) - 1) / 3) for k in range(4)}) if points else []
    for i in ticks:
        x = x_of(i)
        body.append(f'<g class="tick">{_line(x, y, x, y + 3, AXIS_COLOUR)}</g>')
        body.append(_tick_label(x, y + 12, clock(points[i].started_at, zone), CHART_WIDTH))
    return body


def _panel(
    values: Sequence[float | None],
    signals: Sequence[Sequence[int]],
    lines: Sequence[tuple[str, float | None, bool]],
    top: float,
    x_of: Callable[[int], float],
    what: str,
    tr: Say = ENGLISH,
) -> list[str]:
    """One panel of an I-MR chart: the y axis, the centre and limit lines labelled with
    their values, the points joined in run order, points completing a Western Electric
    rule in red with the rules' numbers and a tooltip of value and rules (in the reader's
    language, ``tr``); ``what`` is the
    points' CSS class."""
    shown = [v for v in values if v is not None]
    levels = [v for _, v, _ in lines if v is not None]
    low, high = min([*shown, *levels], default=0.0), max([*shown, *levels], default=1.0)
    pad = (high - low) * 0.05 or abs(high) * 0.01 or 1.0
    low, high = low - pad, high + pad
    bottom, right = top + PANEL - 30, CHART_WIDTH - CHART_RIGHT

    def y_of(value: float) -> float:
        return bottom - (bottom - top) * (value - low) / (high - low)

    body = [_line(CHART_LEFT, top, CHART_LEFT, bottom, AXIS_COLOUR)]
    drawn_lines = sorted(
        (y_of(level), label, level, dashed) for label, level, dashed in lines if level is not None
    )
    label_y = top - LABEL_GAP
    for y, label, level, dashed in drawn_lines:
        colour = LIMIT_COLOUR if dashed else CENTRE_COLOUR
        body.append(_line(CHART_LEFT, y, right, y, colour, dash=dashed))
        # Lines close together (no spread) keep their labels apart, top to bottom.
        label_y = max(y + 3, label_y + LABEL_GAP)
        body.append(_text(right + 3, label_y, f"{label} {number(level)}", colour=colour))
    drawn = [(i, v) for i, v in enumerate(values) if v is not None]
    if drawn:
        path = " ".join(f"{x_of(i):.1f},{y_of(v):.1f}" for i, v in drawn)
        body.append(f'<polyline points="{path}" fill="none" stroke="{BAR_COLOUR}"/>')
    # Size (the report page's 300 kB target, docs/benchmarks.md "report"): the points in
    # control share their group's class and fill, sit on whole pixels and carry no
    # tooltip; a signal has all of its own.
    quiet = [
        f'<circle cx="{x_of(i):.0f}" cy="{y_of(v):.0f}" r="2"/>' for i, v in drawn if not signals[i]
    ]
    body.append(f'<g class="{what}" fill="{BAR_COLOUR}">{"".join(quiet)}</g>')
    for i, v in drawn:
        if rules := signals[i]:
            flag = tr("rule {rules}", rules=", ".join(map(str, rules)))
            body.append(
                f'<circle class="{what} signal" cx="{x_of(i):.1f}" cy="{y_of(v):.1f}" r="3" '
                f'fill="{ALARM_COLOUR}"><title>{number(v)} {flag}</title></circle>'
            )
            body.append(
                _text(x_of(i), y_of(v) - 5, ",".join(map(str, rules)), "middle", ALARM_COLOUR)
                # a white halo: legible where a limit or centre line runs through it
                .replace("<text ", f'<text class="rule" {HALO} ', 1)
            )
    return body


def control_x(i: int, count: int) -> float:
    """Where the ``i``-th of ``count`` runs of a control chart lies along its axis."""
    return CHART_LEFT + (CHART_WIDTH - CHART_LEFT - CHART_RIGHT) * (i / max(count - 1, 1))


#: A trend chart's plot, left and right edge.
TREND_LEFT, TREND_RIGHT = 44, CHART_WIDTH - 12


def trend_x(i: int, count: int) -> float:
    """Where the ``i``-th of ``count`` periods of a trend chart lies along its axis."""
    return TREND_LEFT + (TREND_RIGHT - TREND_LEFT) * (i + 0.5) / max(count, 1)


def control_chart(chart: ControlChart, zone: str = "UTC", tr: Say = ENGLISH) -> str:
    """Individuals (top) and moving ranges (bottom) of the latest runs with their limits,
    a time axis under each (the runs in order, ticks at their start in ``zone``)."""
    points = chart.points
    height = 18 + 2 * PANEL

    def x_of(i: int) -> float:
        return control_x(i, len(points))

    plotted = (
        tr(
            "latest {plotted} of {count} runs in range plotted",
            plotted=len(points),
            count=chart.count,
        )
        if len(points) < chart.count
        else tr(
            "{plotted} of {count} runs in range plotted", plotted=len(points), count=chart.count
        )
    )
    body = [_text(CHART_LEFT, 12, f"{chart.name} ({chart.unit}): {plotted}")]
    body += _panel(
        [p.value for p in points],
        [p.signals for p in points],
        [("UCL", chart.ucl, True), ("x̄", chart.mean, False), ("LCL", chart.lcl, True)],
        18 + 8,
        x_of,
        "point",
        tr,
    )
    body += _time_axis(points, x_of, 18 + PANEL - 22, zone)
    body.append(_text(CHART_LEFT, 18 + PANEL + 4, tr("moving range")))
    body += _panel(
        [p.moving_range for p in points],
        [p.mr_signals for p in points],
        [("UCL", chart.mr_ucl, True), ("MR̄", chart.mr_bar, False)],
        18 + PANEL + 8,
        x_of,
        "mr-point",
        tr,
    )
    body += _time_axis(points, x_of, 18 + 2 * PANEL - 22, zone)
    return _svg(
        tr(
            "I-MR chart of {name}, {plotted} of {count} runs plotted",
            name=chart.name,
            plotted=len(points),
            count=chart.count,
        ),
        body,
        height,
        CHART_WIDTH,
    )


#: A trend chart's colours, one per series.
SERIES_COLOURS = ("#3b6ea5", "#2c7a2c", "#b06a00", "#7a3b8f")


#: A yield axis starts at a multiple of this below its lowest value (with a margin).
PERCENT_STEP = 0.05


def percent_range(values: Sequence[float]) -> tuple[float, float]:
    """A yield axis zoomed on ``values``: from the 5 % step below the lowest value (two
    points of margin) to 100 %, so a drop from 97 to 85 % fills the chart; 0–100 %
    without values."""
    if not values:
        return 0.0, 1.0
    low = math.floor((min(values) - 0.02) / PERCENT_STEP) * PERCENT_STEP
    return max(0.0, min(round(low, 6), 1.0 - PERCENT_STEP)), 1.0


def trend_chart(
    title: str,
    periods: Sequence[tuple[str, str]],
    series: Sequence[tuple[str, Sequence[float | None]]],
    *,
    bars: Sequence[int] | None = None,
    percent_axis: bool = False,
    reference: tuple[str, float] | None = None,
) -> str:
    """Values per period (day or shift; ``periods``: its axis label and its full name):
    ``bars`` (counts) and/or ``series`` of lines (a gap where a period has no value), a
    time axis below, a value axis on the left from 0 with its range labelled (a
    ``percent_axis`` zoomed on its values, :func:`percent_range`), and a ``reference``
    line (a target such as Cpk 1.33)."""
    left, right, top, bottom = TREND_LEFT, TREND_RIGHT, 24, HEIGHT - 22
    levels = [v for _, values in series for v in values if v is not None]
    if reference is not None:
        levels.append(reference[1] * 1.2)
    low, high = (
        percent_range(levels) if percent_axis else (min([0.0, *levels]), max(levels, default=1.0))
    )
    if bars is not None:
        low, high = 0.0, float(max(bars, default=1) or 1)
    if high <= low:
        high = low + (abs(low) or 1.0)

    def x_of(i: int) -> float:
        return trend_x(i, len(periods))

    def y_of(value: float) -> float:
        return bottom - (bottom - top) * (value - low) / (high - low)

    def label(value: float) -> str:
        """A value axis' label; a bound within rounding of zero (a deviation's -1e-13) is 0."""
        value = 0.0 if abs(value) < (high - low) * 1e-9 else value
        return percent(value) if percent_axis else number(value)

    body = [
        _text(left, 12, title),
        _line(left, top, left, bottom, AXIS_COLOUR),
        _line(left, bottom, right, bottom, AXIS_COLOUR),
        _text(left - 3, top + 3, label(high), "end"),
        _text(left - 3, bottom + 3, label(low), "end"),
    ]
    if percent_axis:  # a zoomed axis: its middle too, and a grid line there
        middle = (low + high) / 2
        body.append(_line(left, y_of(middle), right, y_of(middle), "#eee"))
        body.append(_text(left - 3, y_of(middle) + 3, label(middle), "end"))
    if reference is not None:
        name, level = reference
        body.append(_line(left, y_of(level), right, y_of(level), LIMIT_COLOUR, dash=True))
        body.append(
            _text(left + 3, y_of(level) - 3, f"{name} {number(level)}", colour=LIMIT_COLOUR)
        )
    ticks = sorted({round(k * (len(periods) - 1) / 3) for k in range(4)}) if periods else []
    for i in ticks:
        body.append(
            f'<g class="tick">{_line(x_of(i), bottom, x_of(i), bottom + 3, AXIS_COLOUR)}</g>'
        )
        body.append(_tick_label(x_of(i), bottom + 13, periods[i][0], CHART_WIDTH))
    if bars is not None:
        bar_w = max((right - left) / max(len(periods), 1) - 2, 1)
        for i, count in enumerate(bars):
            body.append(
                f'<rect class="bar" x="{x_of(i) - bar_w / 2:.1f}" y="{y_of(count):.1f}" '
                f'width="{bar_w:.1f}" height="{bottom - y_of(count):.1f}" fill="{BAR_COLOUR}">'
                f"<title>{periods[i][1]}: {count}</title></rect>"
            )
    for k, (name, values) in enumerate(series):
        colour = SERIES_COLOURS[k % len(SERIES_COLOURS)]
        legend_x = right - 96 * (len(series) - 1 - k)
        body.append(_text(legend_x, 12, f"— {name}", "end", colour))
        runs: list[list[str]] = [[]]
        points = []
        for i, v in enumerate(values):
            if v is None:
                runs.append([])
                continue
            runs[-1].append(f"{x_of(i):.1f},{y_of(v):.1f}")
            points.append(
                f'<circle cx="{x_of(i):.1f}" cy="{y_of(v):.1f}" r="2">'
                f"<title>{periods[i][1]}: {label(v)}</title></circle>"
            )
        body.append(f'<g class="trend-points" fill="{colour}">{"".join(points)}</g>')
        body += [
            f'<polyline points="{" ".join(run)}" fill="none" stroke="{colour}"/>'
            for run in runs
            if len(run) > 1
        ]
    return _svg(title, body, HEIGHT, CHART_WIDTH)


#: A box plot's size: room on the left for the groups' names, a row per group; as wide
#: as the other charts, so that on a phone (420 px) its text shrinks no more than theirs.
BOX_WIDTH, BOX_LEFT, BOX_RIGHT, BOX_ROW, BOX_TOP = CHART_WIDTH, 130, 20, 22, 24


def box_plots(report: SplitReport, tr: Say = ENGLISH) -> str:
    """One horizontal Tukey box plot per group of ``report`` (box Q1–Q3, median, whiskers
    within the fences, the outliers' count at the right), the limits as red lines."""
    groups = report.groups
    height = BOX_TOP + BOX_ROW * max(len(groups), 1) + 20
    title = tr(
        "{parameter} by {by} ({unit})",
        parameter=report.parameter,
        by=split_name(report.by, tr),
        unit=report.unit,
    )
    if not groups:
        return _svg(title, [_text(BOX_LEFT, BOX_TOP, tr("no values"))], height, BOX_WIDTH)
    ends = [g.minimum for g in groups] + [g.maximum for g in groups]
    ends += [v for v in (report.lower, report.upper) if v is not None]
    low, high = min(ends), max(ends)
    span = (high - low) or 1.0
    low, high = low - 0.03 * span, high + 0.03 * span
    right = BOX_WIDTH - BOX_RIGHT

    def x(value: float) -> float:
        return BOX_LEFT + (value - low) / (high - low) * (right - BOX_LEFT)

    bottom = height - 20
    body = [_text(BOX_LEFT, 12, title)]
    # The spans (from, to) of the axis' labels drawn, so that none is drawn over another.
    spans: list[tuple[float, float]] = []
    for name, limit in (("LSL", report.lower), ("USL", report.upper)):
        if limit is not None:
            label = f"{name} {number(limit)}"
            half = CHAR_WIDTH * len(label) / 2
            spans.append((x(limit) - half, x(limit) + half))
            body.append(_line(x(limit), BOX_TOP - 6, x(limit), bottom, LIMIT_COLOUR, dash=True))
            body.append(_text(x(limit), bottom + 12, label, "middle"))
    for i, g in enumerate(groups):
        mid = BOX_TOP + BOX_ROW * i + BOX_ROW / 2
        label = f"{g.group} (n {g.n})"
        body.append(_text(BOX_LEFT - 6, mid + 3, label[:24], "end"))
        body.append(_line(x(g.whisker_low), mid, x(g.q1), mid, AXIS_COLOUR))
        body.append(_line(x(g.q3), mid, x(g.whisker_high), mid, AXIS_COLOUR))
        for end in (g.whisker_low, g.whisker_high):
            body.append(_line(x(end), mid - 4, x(end), mid + 4, AXIS_COLOUR))
        body.append(
            f'<rect class="box" x="{x(g.q1):.1f}" y="{mid - 7:.1f}" '
            f'width="{max(x(g.q3) - x(g.q1), 1):.1f}" height="14" fill="#dce7f3" '
            f'stroke="{BAR_COLOUR}"/>'
        )
        body.append(_line(x(g.median), mid - 7, x(g.median), mid + 7, BAR_COLOUR))
        if g.outliers:
            colour = ALARM_COLOUR
            body.append(_text(right + 2, mid + 3, f"+{g.outliers}", "start", colour))
    for end, at, anchor in ((low, BOX_LEFT, "start"), (high, right, "end")):
        label = number(end)
        reach = CHAR_WIDTH * len(label)
        left, rightmost = (at, at + reach) if anchor == "start" else (at - reach, at)
        if not any(a < rightmost and left < b for a, b in spans):  # a limit's label is there
            body.append(_text(at, bottom + 12, label, anchor, AXIS_COLOUR))
    return _svg(title, body, height, BOX_WIDTH)
