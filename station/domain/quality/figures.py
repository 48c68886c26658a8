"""The shape of the end-of-line report: one model, rendered as text, CSV, JSON or HTML.

Yields and rates are fractions (0…1), times are seconds, parameter values are in their
``unit``. ``None`` means "not defined for this range" (no runs, no spread, no limit).
"""

from datetime import date, datetime
from typing import Literal

from pydantic import AwareDatetime, BaseModel, ConfigDict, Field

from station.domain.record.records import LimitsRef, Verdict

#: What the end-of-line tester does with a unit: its latest run passed, or not.
Disposition = Literal["ship", "hold"]


class FigurePart(BaseModel):
    """Base of every part of the report's figures: immutable, strict about unknown fields."""

    model_config = ConfigDict(frozen=True, extra="forbid")


class ReportFilter(FigurePart):
    """Which runs the report covers: ``since`` inclusive, ``until`` exclusive (start time),
    and only this station, operator, production lot or product when given."""

    since: AwareDatetime | None = None
    until: AwareDatetime | None = None
    station_id: str | None = None
    operator_id: str | None = None
    lot: str | None = None
    part_number: str | None = None


class Summary(FigurePart):
    """Counts and yields of the runs in range, by the yield definition of
    :mod:`db.rollups`.

    An attempt is a run the operator did not abort (an abort is not an attempt). A
    unit's first and latest attempt are its first and latest attempt *ever* on the line,
    by start time. The units are those whose first attempt is in range (the cohort of
    first-pass and final yield); retests are the attempts in range that are not a unit's
    first. A station's summary counts the units whose first attempt was at the station,
    the station's runs and its own retests, so the stations' summaries add up to the
    line's.
    """

    runs: int
    runs_passed: int
    units_tested: int = Field(description="units whose first attempt (run not aborted) is in range")
    units_passed: int = Field(description="units whose latest attempt passed")
    units_failed: int
    first_pass_units: int = Field(description="units whose first attempt passed")
    report_yield: float | None = Field(description="run yield: passing runs / runs")
    first_pass_yield: float | None = Field(description="units whose first attempt passed / units")
    final_yield: float | None = Field(description="units whose latest attempt passed / units")
    retests: int = Field(
        description="attempts (runs not aborted) in range that are not their unit's first, "
        "each its own station's"
    )
    retest_rate: float | None = Field(description="retests / units")
    aborted_runs: int = Field(
        0,
        description="runs the operator aborted: no attempt, no failure of the unit (not in "
        "the Pareto, not retests); a unit with nothing but aborts is no unit tested",
    )
    hours: float | None = Field(description="length of the range, hours")
    units_per_hour: float | None = Field(
        description="units per hour of station time: 3600 / cycle_time_per_unit_s"
    )
    cycle_time_per_run_s: float | None
    cycle_time_per_unit_s: float | None = Field(description="station time / units")
    cycle_time_per_pose_s: float | None = Field(description="station time / poses")
    poses: int


class StationSummary(FigurePart):
    """The summary of one station."""

    station_id: str
    summary: Summary


class ProductSummary(FigurePart):
    """The summary of one product: the runs of its part number."""

    part_number: str
    summary: Summary


class ParetoEntry(FigurePart):
    """Failing runs whose first failure reason is ``code``."""

    code: str
    count: int
    share: float = Field(description="of all failing runs")
    cumulative_share: float
    by_station: dict[str, int]
    by_operator: dict[str, int]


#: The ages an open hold is counted by (since its latest run started), youngest first.
HOLD_AGES = ("< 1 day", "1–7 days", "> 7 days")


class HoldCount(FigurePart):
    """Open holds of one age or cause."""

    label: str
    units: int


class OpenHolds(FigurePart):
    """The held units the report counts (their latest run failed) that no review has
    closed: no quality review of that latest run (``hold_reviews``)."""

    total: int
    by_age: list[HoldCount] = Field(
        description="per age of the failed run (since its start, at the report's time): "
        + ", ".join(HOLD_AGES)
    )
    by_cause: list[HoldCount] = Field(
        description="per first failure reason of the failed run, most first"
    )


class Histogram(FigurePart):
    """Counts of ``bins`` equal bins from ``start``; outliers land in the end bins."""

    start: float
    width: float
    counts: list[int]


class Distribution(FigurePart):
    """The histogram the page draws: the latest runs' values in bins from the data
    (:func:`station.domain.quality.capability.data_bins`)."""

    edges: list[float] = Field(description="bin edges, one more than counts")
    counts: list[int]
    values: int = Field(description="values, those counted apart included")
    below: int = Field(0, description="values below the far-out fence Q1 − 3·IQR, apart")
    above: int = Field(0, description="values above the far-out fence Q3 + 3·IQR, apart")
    mean: float | None = Field(description="mean of the values binned")
    runs: int = Field(description="the latest runs in range the values are from")


class ParameterStats(FigurePart):
    """Distribution and capability of one parameter against its limits."""

    name: str
    family: str
    unit: str
    lower: float | None
    upper: float | None
    count: int
    mean: float | None
    std: float | None
    min: float | None
    max: float | None
    cp: float | None
    cpk: float | None
    out_of_limits: int
    marginal: int = Field(description="within the limits, within 10 % of the width of one")
    histogram: Histogram
    observed_ppm: float | None = Field(
        None, description="values out of limits per million values, as observed"
    )
    warning: str | None = Field(
        None,
        description="why the normal-theory Cp/Cpk should not be trusted (values out of "
        "limits observed although Cpk says capable), if so",
    )
    distribution: Distribution | None = Field(
        None, description="the histogram drawn: the latest runs' values in bins from the data"
    )


class ChartPoint(FigurePart):
    """One run on a control chart."""

    started_at: datetime
    serial: str
    value: float
    moving_range: float | None
    signals: list[int] = Field(
        description="Western Electric rules (1–4) the value completes on the individuals chart"
    )
    mr_signals: list[int] = Field(
        description="Western Electric rules (1–4) the moving range completes on its chart"
    )


class ControlChart(FigurePart):
    """Individuals and moving-range chart of one coefficient: ``count`` runs in range set
    its limits, the latest of them are ``points``, each with the Western Electric rules
    it completes (:mod:`station.domain.quality.control`) among the points plotted."""

    name: str
    unit: str
    count: int
    mean: float
    mr_bar: float | None
    lcl: float | None
    ucl: float | None
    mr_ucl: float | None
    sigma: float | None = Field(description="short-term σ of the values, MR̄/d₂")
    mr_sigma: float | None = Field(description="σ of the moving ranges, d₃·MR̄/d₂")
    points: list[ChartPoint] = Field(
        description="the latest runs, oldest first (their count is the plotted count)"
    )


class TrendFigures(FigurePart):
    """The figures of one period of the trend: the units whose first run on the line was
    in it, with their first-pass and final yield, its runs, and the Cpk of its values."""

    runs: int
    runs_passed: int
    units: int = Field(description="units whose first run on the line was in the period")
    first_pass_yield: float | None
    final_yield: float | None = Field(description="of the period's units, latest run passed")
    run_yield: float | None = Field(description="passing runs / runs of the period")
    cpk: dict[str, float | None] = Field(description="Cpk per parameter of the period's values")


class TrendDay(TrendFigures):
    """One of the plant's days (in its time zone) of the range."""

    day: date


class TrendShift(TrendFigures):
    """One of the plant's shifts of the range (:mod:`station.domain.quality.shifts`)."""

    day: date = Field(description="the plant day the shift started on")
    shift: str = Field(description="the shift's start time in the plant's zone, HH:MM")
    start: AwareDatetime = Field(description="the shift's start (UTC)")
    end: AwareDatetime = Field(description="the next shift's start (UTC)")


class UnitVerdict(FigurePart):
    """A unit's final state for the ship/hold decision: its latest run (``runs``: every
    run of the unit)."""

    serial: str
    disposition: Disposition
    verdict: Verdict
    runs: int
    last_started_at: datetime
    station_id: str
    operator_id: str
    failure: str | None = Field(description="first failure reason of the latest run")


class VerdictFlip(FigurePart):
    """A unit of the report whose latest run would be judged otherwise."""

    serial: str
    run_id: str = Field(description="the unit's latest run")
    before: Verdict = Field(description="its verdict as stored")
    after: Verdict = Field(description="its verdict under the candidate profile")
    check: str | None = Field(
        description="the check that decides: the candidate's first failure reason of a run "
        "that would fail, the stored one of a run that would pass"
    )


class WhatIf(FigurePart):
    """The report's runs re-judged against a candidate limits profile, nothing stored
    changed: yields, Pareto and capability as they would have been, and the units whose
    verdict would flip."""

    limits: LimitsRef = Field(description="the candidate profile")
    summary: Summary
    pareto: list[ParetoEntry]
    parameters: list[ParameterStats] = Field(description="capability against the candidate")
    pass_to_fail: int = Field(description="runs that passed and would fail")
    fail_to_pass: int = Field(description="runs that failed and would pass")
    flips: list[VerdictFlip] = Field(
        default_factory=list,
        description="units the report counts whose latest run's verdict would flip (the "
        "first of them by serial, `flips_total` in all)",
    )
    flips_total: int = Field(0, description="units whose verdict would flip")
    kept: bool = Field(
        False,
        description="the candidate profile is stored (the what-if was run with a quality "
        "key): `GET /reports/eol?what_if=SHA256` answers it again; an anonymous what-if "
        "stores nothing",
    )


class CoefficientRisk(FigurePart):
    """Global decision risks of one coefficient (JCGM 106:2012 9.5), as fractions of all
    units, from the process's spread and the mean standard uncertainty of measurement.
    They assume a normal population (:mod:`station.domain.quality.risk`); the measured
    values' Anderson–Darling check says whether it is one."""

    name: str
    u: float = Field(description="mean standard uncertainty U/k of the runs that carry one")
    simple_false_accept: float
    simple_false_reject: float
    guarded_false_accept: float = Field(description="with a guard band w = U")
    guarded_false_reject: float
    assumes: Literal["normal population"] = Field(
        "normal population",
        description="the risks' model: a normal process population and measurement error",
    )
    normality_statistic: float | None = Field(
        None,
        description="Anderson–Darling A² of the latest runs' values against a normal "
        "population (None: fewer than 8 values)",
    )
    normality_p_value: float | None = Field(
        None, description="its p-value, interpolated in Stephens' table (0.01…0.15)"
    )
    normality_values: int = Field(0, description="the values the check judged")
    normal: bool | None = Field(
        None,
        description="the values are not rejected as normal at the 5 % level (False: the "
        "risks' model does not describe this population)",
    )


class NearLimits(FigurePart):
    """Passing runs accepted within one expanded uncertainty U of a limit (ILAC-G8): an
    offset or a sensitivity whose value ± U reaches past a bound of the report's limits;
    and the estimated false-accept and false-reject rates of each rule."""

    runs_passed: int = Field(description="passing runs in range that carry uncertainties")
    within_u: int = Field(description="of those, runs with a coefficient within U of a limit")
    units: int = Field(description="units with such a passing run in range")
    risks: list[CoefficientRisk] = Field(
        default_factory=list,
        description="per coefficient, the global false-accept and false-reject rates under "
        "simple and guarded acceptance (normal process and measurement error)",
    )


class ProductSection(FigurePart):
    """One product's statistics in a report whose runs are of several products: its runs
    only (``filter`` narrowed to its part number), judged against its own limits profile
    (the latest of its runs'): capability, distributions, control charts, near-limit runs
    and the Cpk of its trend. No statistic of coefficients spans two products."""

    part_number: str
    filter: ReportFilter = Field(description="the report's filter narrowed to this product")
    bounds_source: str = Field(description="where this product's capability limits come from")
    limits_profiles: list[LimitsRef] = Field(description="profiles its runs were judged by")
    parameters: list[ParameterStats]
    control_charts: list[ControlChart]
    near_limits: NearLimits | None = Field(
        None, description="its passing runs accepted within one U of its limits"
    )
    trend: list[TrendDay] = Field(
        default_factory=list, description="its own trend per plant day, Cpk included"
    )
    shift_trend: list[TrendShift] = Field(
        default_factory=list, description="its own trend per shift, when shifts are configured"
    )


class EolReport(FigurePart):
    """The end-of-line report over ``filter``."""

    generated_at: datetime
    filter: ReportFilter
    bounds_source: str = Field(description="where the capability limits come from")
    limits_profiles: list[LimitsRef] = Field(description="profiles the runs were judged by")
    summary: Summary
    stations: list[StationSummary]
    products: list[ProductSummary] = Field(
        default_factory=list,
        description="per part number, its runs' summary: a unit is one product's, so the "
        "products' rows add up to the line's",
    )
    timezone: str = Field("UTC", description="the plant's time zone the pages show times in")
    trend: list[TrendDay] = Field(
        default_factory=list, description="per plant day of the range, the latest days"
    )
    shifts: list[str] = Field(
        default_factory=list, description="the plant's shift start times (HH:MM), if configured"
    )
    shift_trend: list[TrendShift] = Field(
        default_factory=list,
        description="per shift of the trend's days, when the plant's shifts are configured",
    )
    pareto: list[ParetoEntry]
    parameters: list[ParameterStats]
    control_charts: list[ControlChart]
    units: list[UnitVerdict]
    units_total: int = Field(
        description="units the yield table counts: their first run on the line is in range "
        "and matches the filter (the list may be cut to the latest)"
    )
    units_listed: Literal["all", "held"] = Field(
        "all", description="which units the list holds: all, or the held ones (latest run failed)"
    )
    units_held: int | None = Field(
        None,
        description="of those units, the held ones: their latest run (wherever and whenever "
        "it was) failed; the yield table's failed units",
    )
    open_holds: OpenHolds | None = Field(
        None, description="the held units no review has closed yet, by age and by cause"
    )
    units_offset: int = Field(0, description="units before this page of the list, newest first")
    units_limit: int | None = Field(None, description="the most units a page of the list holds")
    what_if: WhatIf | None = Field(
        None, description="the runs re-judged against a candidate limits profile, when given"
    )
    near_limits: NearLimits | None = Field(
        None, description="passing runs accepted within one U of a limit (None: no limits to judge)"
    )
    product_sections: list[ProductSection] = Field(
        default_factory=list,
        description="when the runs in range are of more than one product: each product's "
        "statistics against its own limits profile; the report's own `parameters`, "
        "`control_charts`, `near_limits` and trend Cpk are then empty (never one statistic "
        "over two products), its counts and yields the line's",
    )
