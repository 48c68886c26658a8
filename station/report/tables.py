"""The summary and parameter tables' cells, shared by the text and HTML renderings."""

from station.domain.quality.figures import EolReport, ProductSection, Summary
from station.report.formatting import number, percent, seconds

#: What holds a set of statistics of coefficients: a report over one product's runs, or
#: a product's section of a report over several.
Statistics = EolReport | ProductSection


def statistics_of(report: EolReport) -> list[Statistics]:
    """The report's sets of statistics of coefficients: its own over one product's runs,
    or each product's section over several products' runs."""
    sections: list[Statistics] = [*report.product_sections]
    return sections or [report]


SUMMARY_HEADER = [
    "",
    "units",
    "passed",
    "failed",
    "runs",
    "run yield",
    "first-pass yield",
    "final yield",
    "retests",
    "retest rate",
    "aborts",
    "units/h",
    "s/unit",
    "s/pose",
]


def summary_cells(name: str, s: Summary) -> list[str]:
    """One summary as table cells (text and HTML)."""
    return [
        name,
        number(s.units_tested),
        number(s.units_passed),
        number(s.units_failed),
        number(s.runs),
        percent(s.report_yield),
        percent(s.first_pass_yield),
        percent(s.final_yield),
        number(s.retests),
        percent(s.retest_rate),
        number(s.aborted_runs),
        number(s.units_per_hour),
        seconds(s.cycle_time_per_unit_s),
        seconds(s.cycle_time_per_pose_s),
    ]


PARAMETER_HEADER = [
    "parameter",
    "unit",
    "n",
    "mean",
    "std",
    "min",
    "max",
    "LSL",
    "USL",
    "Cp",
    "Cpk",
    "out",
    "ppm out",
    "marginal",
]


def parameter_cells(report: Statistics) -> list[list[str]]:
    """The parameter table's cells (text and HTML)."""
    return [
        [
            p.name,
            p.unit,
            number(p.count),
            number(p.mean),
            number(p.std),
            number(p.min),
            number(p.max),
            number(p.lower),
            number(p.upper),
            number(p.cp),
            number(p.cpk),
            number(p.out_of_limits),
            number(p.observed_ppm),
            number(p.marginal),
        ]
        for p in report.parameters
    ]


def listed(report: EolReport) -> str:
    """What the unit list holds: ``3 of 12 held``, ``1–50 of 6020``."""
    total = report.units_held if report.units_listed == "held" else report.units_total
    which = " held" if report.units_listed == "held" else ""
    if not report.units:
        return f"none of {total}{which}"
    first = report.units_offset + 1
    return f"{first}–{report.units_offset + len(report.units)} of {total}{which}"


WHAT_IF_HEADER = ["", "current", "what-if"]
CAPABILITY_HEADER = ["parameter", "Cpk", "Cpk what-if", "out", "out what-if"]


def what_if_cells(report: EolReport) -> list[list[str]]:
    """The yields now and under the candidate profile (text and HTML)."""
    w = report.what_if
    if w is None:
        return []
    now, then = report.summary, w.summary
    return [
        ["runs passed", number(now.runs_passed), number(then.runs_passed)],
        ["run yield", percent(now.report_yield), percent(then.report_yield)],
        ["first-pass yield", percent(now.first_pass_yield), percent(then.first_pass_yield)],
        ["final yield", percent(now.final_yield), percent(then.final_yield)],
        ["units passed", number(now.units_passed), number(then.units_passed)],
        ["runs that would fail", "", number(w.pass_to_fail)],
        ["runs that would pass", "", number(w.fail_to_pass)],
    ]


FLIP_HEADER = ["serial (verdict would flip)", "verdict", "check"]


def flip_cells(report: EolReport) -> list[list[str]]:
    """The units whose verdict would flip under the candidate (text)."""
    w = report.what_if
    return (
        []
        if w is None
        else [[f.serial, f"{f.before} → {f.after}", f.check or "–"] for f in w.flips]
    )


def capability_cells(report: EolReport) -> list[list[str]]:
    """Each parameter's Cpk and values out of limits, now and under the candidate."""
    w = report.what_if
    if w is None:
        return []
    now = {p.name: p for p in report.parameters}
    return [
        [
            p.name,
            number(now[p.name].cpk) if p.name in now else "–",
            number(p.cpk),
            number(now[p.name].out_of_limits) if p.name in now else "–",
            number(p.out_of_limits),
        ]
        for p in w.parameters
    ]


def near_limits_line(report: Statistics) -> str:
    """The passing runs accepted within one U of a limit, in words (text and HTML)."""
    near = report.near_limits
    if near is None:
        return ""
    return (
        f"Accepted within one U of a limit: {near.within_u} of {near.runs_passed} passing runs "
        f"with uncertainties ({near.units} units): an offset or sensitivity whose value ± U "
        "reaches past a limit (guarded acceptance, w = U, would refuse them)"
    )


#: The decision risks' table: per coefficient, both rules (JCGM 106 global risks).
RISK_HEADER = [
    "coefficient",
    "u (U/k)",
    "simple: false accept",
    "simple: false reject",
    "guarded: false accept",
    "guarded: false reject",
]


def risk_cells(report: Statistics) -> list[list[str]]:
    """The rows of :data:`RISK_HEADER`, one per coefficient with an uncertainty."""
    near = report.near_limits
    if near is None:
        return []
    return [
        [
            r.name,
            number(r.u),
            percent(r.simple_false_accept),
            percent(r.simple_false_reject),
            percent(r.guarded_false_accept),
            percent(r.guarded_false_reject),
        ]
        for r in near.risks
    ]
