"""Charts as inline SVG, drawn on the server: histograms with limit lines, the failure
Pareto, individuals and moving-range (I-MR) control charts. No script, no external file.
"""

from collections.abc import Sequence
from xml.sax.saxutils import escape

from station.quality.figures import ControlChart, ParameterStats, ParetoEntry
from station.report.formatting import number, percent

WIDTH, HEIGHT, PAD = 360, 150, 28
LIMIT_COLOUR, CENTRE_COLOUR, BAR_COLOUR, ALARM_COLOUR = "#c0392b", "#2c7a2c", "#3b6ea5", "#c0392b"


def _svg(title: str, body: Sequence[str], height: int = HEIGHT) -> str:
    return (
        f'<svg class="chart" role="img" xmlns="http://www.w3.org/2000/svg" '
        f'viewBox="0 0 {WIDTH} {height}" width="{WIDTH}" height="{height}">'
        f"<title>{escape(title)}</title>{''.join(body)}</svg>"
    )


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


def histogram(stats: ParameterStats) -> str:
    """Bars of the histogram, red lines at the limits."""
    h = stats.histogram
    span = h.width * len(h.counts)
    plot_w, plot_h = WIDTH - 2 * PAD, HEIGHT - 2 * PAD
    top = max(h.counts) or 1

    def x_of(value: float) -> float:
        return PAD + plot_w * (value - h.start) / span

    body = [_line(PAD, HEIGHT - PAD, WIDTH - PAD, HEIGHT - PAD, "#999")]
    bar_w = plot_w / len(h.counts)
    for i, count in enumerate(h.counts):
        if count:
            bar_h = plot_h * count / top
            body.append(
                f'<rect class="bar" x="{PAD + i * bar_w:.1f}" y="{HEIGHT - PAD - bar_h:.1f}" '
                f'width="{max(bar_w - 1, 1):.1f}" height="{bar_h:.1f}" fill="{BAR_COLOUR}">'
                f"<title>{count}</title></rect>"
            )
    for label, limit in (("LSL", stats.lower), ("USL", stats.upper)):
        if limit is not None:
            x = x_of(limit)
            body.append(_line(x, PAD - 8, x, HEIGHT - PAD, LIMIT_COLOUR))
            body.append(_text(x, PAD - 10, f"{label} {number(limit)}", "middle", LIMIT_COLOUR))
    body.append(_text(PAD, HEIGHT - 8, number(h.start)))
    body.append(_text(WIDTH - PAD, HEIGHT - 8, number(h.start + span), "end"))
    body.append(_text(WIDTH / 2, HEIGHT - 8, f"{stats.name} ({stats.unit})", "middle"))
    return _svg(f"histogram of {stats.name}", body)


def pareto(entries: Sequence[ParetoEntry]) -> str:
    """Failing runs per first failure reason, largest first, with the cumulative share."""
    rows = list(entries)[:10]
    row_h = 18
    height = max(len(rows), 1) * row_h + 2 * 10
    label_w, plot_w = 150, WIDTH - 150 - 60
    top = max((e.count for e in rows), default=1)
    body = []
    for i, entry in enumerate(rows):
        y = 10 + i * row_h
        bar = plot_w * entry.count / top
        body.append(_text(label_w - 4, y + 12, entry.code[:28], "end"))
        body.append(
            f'<rect class="bar" x="{label_w}" y="{y + 2}" width="{max(bar, 1):.1f}" '
            f'height="{row_h - 4}" fill="{BAR_COLOUR}"><title>{entry.count}</title></rect>'
        )
        body.append(
            _text(label_w + bar + 4, y + 12, f"{entry.count} ({percent(entry.cumulative_share)})")
        )
    if not rows:
        body.append(_text(WIDTH / 2, 24, "no failures", "middle"))
    return _svg("failure Pareto", body, height)


def control_chart(chart: ControlChart) -> str:
    """Individuals (top) and moving ranges (bottom) of the latest runs with their limits."""
    points = chart.points
    height = 2 * HEIGHT - PAD
    plot_w = WIDTH - 2 * PAD
    i_top, i_bottom = PAD, HEIGHT - PAD
    mr_top, mr_bottom = HEIGHT, height - PAD
    values = [p.value for p in points]
    ranges = [p.moving_range for p in points if p.moving_range is not None]
    low = min([*values, *(v for v in (chart.lcl, chart.mean) if v is not None)])
    high = max([*values, *(v for v in (chart.ucl, chart.mean) if v is not None)])
    high = high if high > low else low + 1
    mr_high = max([*ranges, chart.mr_ucl or 0.0]) or 1.0

    def x_of(i: int) -> float:
        return PAD + plot_w * (i / max(len(points) - 1, 1))

    def y_i(value: float) -> float:
        return i_bottom - (i_bottom - i_top) * (value - low) / (high - low)

    def y_mr(value: float) -> float:
        return mr_bottom - (mr_bottom - mr_top) * value / mr_high

    body = [_text(PAD, 12, f"{chart.name} ({chart.unit}), {chart.count} runs")]
    body.append(_line(PAD, y_i(chart.mean), WIDTH - PAD, y_i(chart.mean), CENTRE_COLOUR))
    body.append(_text(WIDTH - PAD + 2, y_i(chart.mean) + 3, "x̄", colour=CENTRE_COLOUR))
    for label, limit in (("UCL", chart.ucl), ("LCL", chart.lcl)):
        if limit is not None:
            body.append(_line(PAD, y_i(limit), WIDTH - PAD, y_i(limit), LIMIT_COLOUR, dash=True))
            body.append(_text(WIDTH - PAD + 2, y_i(limit) + 3, label, colour=LIMIT_COLOUR))
    if chart.mr_bar is not None and chart.mr_ucl is not None:
        body.append(_line(PAD, y_mr(chart.mr_bar), WIDTH - PAD, y_mr(chart.mr_bar), CENTRE_COLOUR))
        body.append(
            _line(PAD, y_mr(chart.mr_ucl), WIDTH - PAD, y_mr(chart.mr_ucl), LIMIT_COLOUR, True)
        )
        body.append(_text(WIDTH - PAD + 2, y_mr(chart.mr_ucl) + 3, "UCL", colour=LIMIT_COLOUR))
    body.append(_text(PAD, mr_top - 4, "moving range"))
    if points:
        path = " ".join(f"{x_of(i):.1f},{y_i(p.value):.1f}" for i, p in enumerate(points))
        body.append(f'<polyline points="{path}" fill="none" stroke="{BAR_COLOUR}"/>')
        mr_path = " ".join(
            f"{x_of(i):.1f},{y_mr(p.moving_range):.1f}"
            for i, p in enumerate(points)
            if p.moving_range is not None
        )
        if mr_path:
            body.append(f'<polyline points="{mr_path}" fill="none" stroke="{BAR_COLOUR}"/>')
        for i, p in enumerate(points):
            alarm = bool(chart.mr_bar) and (
                (chart.ucl is not None and p.value > chart.ucl)
                or (chart.lcl is not None and p.value < chart.lcl)
            )
            colour = ALARM_COLOUR if alarm else BAR_COLOUR
            body.append(
                f'<circle class="point" cx="{x_of(i):.1f}" cy="{y_i(p.value):.1f}" r="2" '
                f'fill="{colour}"><title>{escape(p.serial)} {number(p.value, 6)}</title></circle>'
            )
    return _svg(f"I-MR chart of {chart.name}", body, height)
