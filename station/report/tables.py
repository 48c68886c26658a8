"""The summary and parameter tables' cells, shared by the text and HTML renderings."""

from station.quality.figures import EolReport, Summary
from station.report.formatting import number, percent, seconds

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
    "marginal",
]


def parameter_cells(report: EolReport) -> list[list[str]]:
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
