"""Process capability, histogram bins and individuals control-chart limits.

Capability against the limits (Montgomery, *Introduction to Statistical Quality
Control*, ch. 8), with μ and σ the mean and sample standard deviation of the values::

    Cp  = (USL − LSL) / 6σ
    Cpk = min(USL − μ, μ − LSL) / 3σ        (one-sided: the side that has a limit)

σ is the overall standard deviation of every value in the range, so in the AIAG
vocabulary these are the performance indices Pp and Ppk; the control chart below uses
the short-term σ = MR̄/d₂ instead.

Individuals and moving-range (I-MR) chart (Montgomery, ch. 6), MRᵢ = |xᵢ − xᵢ₋₁|::

    I chart:  centre x̄,  limits x̄ ± 3·MR̄/d₂ = x̄ ± 2.66·MR̄
    MR chart: centre MR̄, upper limit D₄·MR̄ = 3.267·MR̄

A value is *marginal* when it is within the limits but closer to one of them than
:data:`MARGIN` of the tolerance width (USL − LSL; a one-sided limit counts from 0).
"""

import math
from collections.abc import Sequence

import numpy as np

#: d₂ of subgroups of two (a moving range spans two values).
D2 = 1.128
#: D₄ of subgroups of two.
D4 = 3.267
#: Fraction of the tolerance width next to a limit where a value counts as marginal.
MARGIN = 0.10
#: Histogram bins, and how far past the limits the histogram reaches (fraction of width).
HISTOGRAM_BINS = 30
HISTOGRAM_OVERHANG = 0.25
#: The Cpk a process in production is read as capable at (AIAG: 1.33).
CAPABLE_CPK = 1.33
#: Relative size of the rounding left in a one-pass sum of squares.
ROUNDING = 1e-12


def tolerance(lower: float | None, upper: float | None) -> tuple[float, float]:
    """The tolerance band: the limits, a missing side replaced by 0."""
    return (0.0 if lower is None else lower, 0.0 if upper is None else upper)


def marginal_zones(lower: float | None, upper: float | None) -> tuple[float, float]:
    """``(a, b)``: a value in ``[lower, a)`` or ``(b, upper]`` is marginal."""
    low, high = tolerance(lower, upper)
    width = high - low
    return (low + MARGIN * width, high - MARGIN * width)


def histogram_bins(lower: float | None, upper: float | None) -> tuple[float, float, int]:
    """``(first edge, bin width, bins)`` covering the limits and a quarter width past them.

    A one-sided limit starts at 0 (errors and noise are not negative). Values outside
    the range are counted in the first or last bin.
    """
    low, high = tolerance(lower, upper)
    width = high - low
    start = low - HISTOGRAM_OVERHANG * width if lower is not None else low
    end = high + HISTOGRAM_OVERHANG * width
    return (start, (end - start) / HISTOGRAM_BINS, HISTOGRAM_BINS)


def cp(std: float | None, lower: float | None, upper: float | None) -> float | None:
    """Cp; ``None`` without two limits or without spread."""
    if std is None or std <= 0 or lower is None or upper is None:
        return None
    return (upper - lower) / (6 * std)


def cpk(
    mean: float | None, std: float | None, lower: float | None, upper: float | None
) -> float | None:
    """Cpk (one-sided when one limit is missing); ``None`` without limits or spread."""
    if mean is None or std is None or std <= 0 or (lower is None and upper is None):
        return None
    sides = [
        (upper - mean) / (3 * std) if upper is not None else math.inf,
        (mean - lower) / (3 * std) if lower is not None else math.inf,
    ]
    return min(sides)


def shifted_moments(
    count: int, shifted_sum: float, shifted_squares: float, shift: float
) -> tuple[float | None, float | None]:
    """Mean and sample standard deviation from Σ(x − c) and Σ(x − c)² (c = ``shift``).

    Summing about a value near the data keeps the one-pass variance free of
    cancellation (Chan, Golub & LeVeque 1983, the shifted data algorithm).
    """
    if count == 0:
        return (None, None)
    mean_shifted = shifted_sum / count
    if count == 1:
        return (shift + mean_shifted, None)
    spread = shifted_squares - shifted_sum * mean_shifted
    # Rounding leaves ~1e-16 of the summed squares where every value is the same.
    if spread <= ROUNDING * shifted_squares:
        return (shift + mean_shifted, 0.0)
    return (shift + mean_shifted, math.sqrt(spread / (count - 1)))


def individuals_limits(mean: float, mr_bar: float) -> tuple[float, float, float]:
    """``(LCL, UCL, MR UCL)`` of the I-MR chart."""
    sigma = mr_bar / D2
    return (mean - 3 * sigma, mean + 3 * sigma, D4 * mr_bar)


def observed_ppm(out_of_limits: int, count: int) -> float | None:
    """Values out of limits per million values, as observed (no distribution assumed)."""
    return None if not count else 1e6 * out_of_limits / count


def capability_warning(cpk_value: float | None, out_of_limits: int, count: int) -> str | None:
    """Why a normal-theory Cpk should not be trusted here, or ``None``: values out of
    limits were observed although Cpk says capable (it predicts well under 100 ppm), so
    the values are not one normal population (two populations, a shift, outliers)."""
    if cpk_value is None or cpk_value < CAPABLE_CPK or not out_of_limits:
        return None
    ppm = observed_ppm(out_of_limits, count) or 0.0
    return (
        f"{out_of_limits} of {count} values out of limits ({ppm:.0f} ppm observed) although "
        f"Cpk {cpk_value:.2f} says capable: the values are not one normal population "
        "(two populations, a shift or outliers); read the observed ppm, not Cpk"
    )


#: The most bins a histogram drawn from the data gets (the page's size).
MAX_DATA_BINS = 30
#: Tukey's far-out fences: values beyond Q1 − k·IQR or Q3 + k·IQR are binned apart.
FAR_OUT = 3.0
#: Values whose span is within this fraction of their magnitude (or below the smallest
#: normal double) are one value to the histogram: bins narrower than a few doubles'
#: spacing cannot be made (a solver's ``32276.0`` beside ``32276.000000000004``), so
#: they get one bin around them, :data:`ONE_VALUE_HALF_WIDTH` of it either side.
SAME_VALUE = 1e-9
ONE_VALUE_HALF_WIDTH = 1e-6
SMALLEST_SPAN = float(np.finfo(float).smallest_normal)


def data_bins(values: Sequence[float]) -> tuple[list[float], list[int], int, int]:
    """Bins from the values themselves: edges, counts, and the values below and above
    Tukey's far-out fences (``Q1 − 3·IQR``, ``Q3 + 3·IQR``), counted apart so a few
    outliers do not squeeze the rest into one bar. The bins span the values within the
    fences, of the Freedman–Diaconis width (``2·IQR·n^(-1/3)`` of all n values; Sturges'
    ``⌈log₂ n⌉ + 1`` bins where the IQR is 0), at most :data:`MAX_DATA_BINS`; values
    within :data:`SAME_VALUE` of each other are one value, in one bin around it."""
    data = np.asarray(values, dtype=float)
    if data.size == 0:
        return [], [], 0, 0
    q1, q3 = (float(q) for q in np.percentile(data, [25, 75]))
    spread = q3 - q1
    low, high = float(data.min()), float(data.max())
    if spread > 0:
        low, high = max(low, q1 - FAR_OUT * spread), min(high, q3 + FAR_OUT * spread)
    inside = data[(data >= low) & (data <= high)]
    below, above = int((data < low).sum()), int((data > high).sum())
    scale = max(abs(low), abs(high))
    one_value = high - low <= max(SAME_VALUE * scale, SMALLEST_SPAN)
    if one_value:
        half = max(scale * ONE_VALUE_HALF_WIDTH, SMALLEST_SPAN / ONE_VALUE_HALF_WIDTH)
        low, high = low - half, high + half
        bins = 1
    elif spread > 0:
        bins = math.ceil((high - low) / (2 * spread * data.size ** (-1 / 3)))
    else:
        bins = math.ceil(math.log2(data.size)) + 1
    counts, edges = np.histogram(inside, bins=min(bins, MAX_DATA_BINS), range=(low, high))
    return [float(e) for e in edges], [int(c) for c in counts], below, above
