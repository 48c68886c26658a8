"""The summary and parameter tables' cells, shared by the text and HTML renderings.

Headers and words are in the reader's language (``tr``: :func:`station.domain.i18n.speaker`;
English by default, as the text report is); values and names as stored.
"""

import re
from collections.abc import Callable

from station.domain.i18n import ENGLISH, Say
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


def summary_header(tr: Say = ENGLISH) -> list[str]:
    """The summary table's header (its first column, the row's name, has none)."""
    return [
        "",
        tr("units"),
        tr("passed"),
        tr("failed"),
        tr("runs"),
        tr("run yield"),
        tr("first-pass yield"),
        tr("final yield"),
        tr("retests"),
        tr("retest rate"),
        tr("aborts"),
        tr("units/h"),
        tr("s/unit"),
        tr("s/pose"),
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


def parameter_header(tr: Say = ENGLISH) -> list[str]:
    """The parameter table's header."""
    return [
        tr("parameter"),
        tr("unit"),
        "n",
        tr("mean"),
        tr("std"),
        tr("min"),
        tr("max"),
        "LSL",
        "USL",
        "Cp",
        "Cpk",
        tr("out"),
        tr("ppm out"),
        tr("marginal"),
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


def listed(report: EolReport, tr: Say = ENGLISH) -> str:
    """What the unit list holds: ``3 of 12 held``, ``1–50 of 6020``."""
    held = report.units_listed == "held"
    total = report.units_held if held else report.units_total
    if not report.units:
        return (
            tr("none of {total} held", total=total) if held else tr("none of {total}", total=total)
        )
    first, last = report.units_offset + 1, report.units_offset + len(report.units)
    if held:
        return tr("{first}–{last} of {total} held", first=first, last=last, total=total)
    return tr("{first}–{last} of {total}", first=first, last=last, total=total)


def what_if_header(tr: Say = ENGLISH) -> list[str]:
    """The what-if table's header: the yields now and under the candidate."""
    return ["", tr("current"), tr("what-if")]


def capability_header(tr: Say = ENGLISH) -> list[str]:
    """The what-if capability table's header."""
    return [tr("parameter"), "Cpk", tr("Cpk what-if"), tr("out"), tr("out what-if")]


def what_if_cells(report: EolReport, tr: Say = ENGLISH) -> list[list[str]]:
    """The yields now and under the candidate profile (text and HTML)."""
    w = report.what_if
    if w is None:
        return []
    now, then = report.summary, w.summary
    return [
        [tr("runs passed"), number(now.runs_passed), number(then.runs_passed)],
        [tr("run yield"), percent(now.report_yield), percent(then.report_yield)],
        [tr("first-pass yield"), percent(now.first_pass_yield), percent(then.first_pass_yield)],
        [tr("final yield"), percent(now.final_yield), percent(then.final_yield)],
        [tr("units passed"), number(now.units_passed), number(then.units_passed)],
        [tr("runs that would fail"), "", number(w.pass_to_fail)],
        [tr("runs that would pass"), "", number(w.fail_to_pass)],
    ]


def flip_header(tr: Say = ENGLISH) -> list[str]:
    """The header of the units whose verdict would flip (text)."""
    return [tr("serial (verdict would flip)"), tr("verdict"), tr("check")]


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


def near_limits_line(report: Statistics, tr: Say = ENGLISH) -> str:
    """The passing runs accepted within one U of a limit, in words (text and HTML)."""
    near = report.near_limits
    if near is None:
        return ""
    return tr(
        "Accepted within one U of a limit: {within} of {passed} passing runs with "
        "uncertainties ({units} units): an offset or sensitivity whose value ± U reaches "
        "past a limit (guarded acceptance, w = U, would refuse them)",
        within=near.within_u,
        passed=near.runs_passed,
        units=near.units,
    )


def risk_header(tr: Say = ENGLISH) -> list[str]:
    """The decision risks' table header: per coefficient, both rules (JCGM 106 global
    risks)."""
    return [
        tr("coefficient"),
        "u (U/k)",
        tr("simple: false accept"),
        tr("simple: false reject"),
        tr("guarded: false accept"),
        tr("guarded: false reject"),
    ]


def risk_cells(report: Statistics) -> list[list[str]]:
    """The rows of :func:`risk_header`, one per coefficient with an uncertainty."""
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


def split_name(by: str, tr: Say = ENGLISH) -> str:
    """A split's column (:data:`station.domain.quality.split.SplitBy`) in words."""
    names = {
        "station": tr("station"),
        "lot": tr("lot"),
        "operator": tr("operator"),
        "fixture_slot": tr("fixture slot"),
        "part_number": tr("product"),
        "software_version": tr("software version"),
    }
    return names.get(by, by.replace("_", " "))


#: Where a report's limits come from (``bounds_source``, :func:`db.report.reports.report_bounds`
#: and :mod:`db.report.split` word it in English): each wording, its line for the reader.
_SOURCES: tuple[tuple[re.Pattern[str], Callable[[Say, dict[str, str]], str]], ...] = (
    (
        re.compile(r"limits profile (?P<name>.+) \(every run in range\)"),
        lambda tr, v: tr("limits profile {name} (every run in range)", **v),
    ),
    (
        re.compile(
            r"limits profile (?P<name>.+) \(the latest run's, of (?P<count>\d+) profiles in range\)"
        ),
        lambda tr, v: tr(
            "limits profile {name} (the latest run's, of {count} profiles in range)", **v
        ),
    ),
    (
        re.compile(r"limits profile (?P<name>.+) \(the latest run's whose profile is stored\)"),
        lambda tr, v: tr("limits profile {name} (the latest run's whose profile is stored)", **v),
    ),
    (
        re.compile(
            r"(?P<what>the bounds the roll-ups were counted with|no limits) "
            r"\((?P<missing>no run in range|no profile of the runs in range stored)\)"
            r"(: no capability)?"
        ),
        lambda tr, v: (
            tr(
                "the bounds the roll-ups were counted with ({missing})",
                missing=_missing(tr, v["missing"]),
            )
            if v["what"] != "no limits"
            else tr("no limits ({missing}): no capability", missing=_missing(tr, v["missing"]))
        ),
    ),
    (
        re.compile(r"each product against its own limits profile \((?P<count>\d+) products\)"),
        lambda tr, v: tr("each product against its own limits profile ({count} products)", **v),
    ),
    (
        re.compile(
            r"each product against its own limits profile \((?P<count>\d+) products in range\)"
        ),
        lambda tr, v: tr(
            "each product against its own limits profile ({count} products in range)", **v
        ),
    ),
    (re.compile(r"no limits"), lambda tr, v: tr("no limits")),
)


def _missing(tr: Say, missing: str) -> str:
    return (
        tr("no run in range")
        if missing == "no run in range"
        else tr("no profile of the runs in range stored")
    )


#: What :func:`db.report.reports.report_bounds`' wording gets when the statistics are the runs'.
NOT_ROLLED_UP = "; statistics from the runs, not the roll-ups' other bounds"


def source_words(source: str, tr: Say = ENGLISH) -> str:
    """Where a report's limits come from (its ``bounds_source``) in the reader's language
    (``tr``); a wording not known here as it is."""
    source, rolled, _ = source.partition(NOT_ROLLED_UP)
    if rolled:
        return source_words(source, tr) + tr(
            "; statistics from the runs, not the roll-ups' other bounds"
        )
    for pattern, words in _SOURCES:
        if found := pattern.fullmatch(source):
            return words(tr, {k: v for k, v in found.groupdict().items() if v is not None})
    return source


def capability_words(
    out_of_limits: int, count: int, ppm: float | None, cpk: float | None, tr: Say = ENGLISH
) -> str:
    """Why a normal-theory Cpk should not be trusted (a parameter's or a group's
    ``warning``, :func:`station.domain.quality.capability.capability_warning`) in the
    reader's language (``tr``), from its figures."""
    return tr(
        "{out} of {count} values out of limits ({ppm} ppm observed) although Cpk {cpk} says "
        "capable: the values are not one normal population (two populations, a shift or "
        "outliers); read the observed ppm, not Cpk",
        out=out_of_limits,
        count=count,
        ppm=f"{ppm or 0.0:.0f}",
        cpk=f"{cpk or 0.0:.2f}",
    )
