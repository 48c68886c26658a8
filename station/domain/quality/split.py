"""A parameter's distribution and capability split by a run's station, lot, operator,
fixture slot, product or software version: one box plot and one row of figures per group.

Box plots after Tukey: the box from the first to the third quartile (linear interpolation
between order statistics, Hyndman & Fan type 7) with the median, whiskers to the most
extreme values within the fences Q1 − 1.5·IQR and Q3 + 1.5·IQR, the values beyond them
counted as outliers. Beside the normal-theory Cpk, the observed ppm out of limits and the
report's warning when they disagree (:func:`capability_warning`).
"""

from collections.abc import Sequence
from typing import Literal

import numpy as np
from pydantic import Field

from station.domain.quality.capability import capability_warning, cpk, observed_ppm
from station.domain.quality.figures import FigurePart, ReportFilter

#: What a parameter may be split by: a run's column each.
SplitBy = Literal["station", "lot", "operator", "fixture_slot", "part_number", "software_version"]
#: Tukey's inner fences: Q1 − k·IQR, Q3 + k·IQR.
FENCE = 1.5
#: The label of the runs without a value of the split (a run without a lot).
NO_VALUE = "(none)"


class GroupStats(FigurePart):
    """One group's values of the parameter: n, mean, sd, the box plot's five numbers,
    outliers, Cpk and the observed ppm out of limits."""

    group: str
    n: int
    mean: float
    sd: float | None = Field(description="sample standard deviation; None for one value")
    minimum: float
    q1: float
    median: float
    q3: float
    maximum: float
    whisker_low: float = Field(description="lowest value within Q1 − 1.5·IQR")
    whisker_high: float = Field(description="highest value within Q3 + 1.5·IQR")
    outliers: int = Field(description="values beyond the fences")
    out_of_limits: int
    cpk: float | None
    ppm_observed: float | None
    warning: str | None = Field(
        None, description="why the normal-theory Cpk disagrees with the observed ppm"
    )


class SplitReport(FigurePart):
    """``parameter`` over the runs ``filter`` selects (the latest ``sample_limit`` of
    them: ``sampled_runs``), split by ``by``: the largest groups first; over runs of
    several products, a section per product instead."""

    parameter: str
    unit: str
    by: SplitBy
    filter: ReportFilter
    lower: float | None
    upper: float | None
    bounds_source: str
    sampled_runs: int
    sample_limit: int
    groups: list[GroupStats]
    groups_total: int = Field(description="groups in the sample (the page shows the largest)")
    part_number: str | None = Field(
        None, description="the product of a section (its runs only, against its own limits)"
    )
    sections: list["SplitReport"] = Field(
        default_factory=list,
        description="when the runs are of more than one product: the split of each product's "
        "runs against its own limits profile; the report's own `groups` are then empty "
        "(a group's Cpk never spans two products)",
    )


def group_stats(
    group: str, values: Sequence[float], lower: float | None, upper: float | None
) -> GroupStats:
    """The figures of one group's ``values`` (at least one) against ``lower``/``upper``."""
    data = np.sort(np.asarray(values, dtype=float))
    q1, median, q3 = (float(q) for q in np.percentile(data, [25, 50, 75]))
    iqr = q3 - q1
    low_fence, high_fence = q1 - FENCE * iqr, q3 + FENCE * iqr
    # Each whisker from its own side: values a few doubles apart may have both
    # quartiles (interpolated) between two neighbours, and no value within the fences.
    above_low, below_high = data[data >= low_fence], data[data <= high_fence]
    mean = float(data.mean())
    sd = float(data.std(ddof=1)) if data.size > 1 else None
    out = int(np.count_nonzero(data < lower)) if lower is not None else 0
    out += int(np.count_nonzero(data > upper)) if upper is not None else 0
    capability = cpk(mean, sd, lower, upper)
    return GroupStats(
        group=group,
        n=int(data.size),
        mean=mean,
        sd=sd,
        minimum=float(data[0]),
        q1=q1,
        median=median,
        q3=q3,
        maximum=float(data[-1]),
        whisker_low=float(above_low[0]),
        whisker_high=float(below_high[-1]),
        outliers=int(data.size - above_low.size + data.size - below_high.size),
        out_of_limits=out,
        cpk=capability,
        ppm_observed=observed_ppm(out, int(data.size)),
        warning=capability_warning(capability, out, int(data.size)),
    )
