"""Western Electric rules for a control chart's points (out-of-control patterns).

With centre line c and the chart's σ (Western Electric, *Statistical Quality Control
Handbook*, 1956; Montgomery, *Introduction to Statistical Quality Control*, §5.3.6), a
point signals when it completes

1. one point beyond 3σ from the centre;
2. two of three consecutive points beyond 2σ, on the same side;
3. four of five consecutive points beyond 1σ, on the same side;
4. eight consecutive points on the same side of the centre.

The point flagged is the one that completes the pattern (the last of its window), as
Minitab and most SPC software flag it. The individuals chart uses c = x̄ and
σ = MR̄/d₂; the moving-range chart c = MR̄ and σ_MR = d₃·MR̄/d₂ (d₃ = 0.853 for ranges
of two), whose lower zones lie below zero when 3σ_MR exceeds MR̄, so rules 1 and 2
signal only above its centre there. A point on the centre line is on neither side.
"""

from collections.abc import Sequence

from station.domain.quality.capability import D2

#: d₃ of subgroups of two: the standard deviation of a moving range over σ.
D3 = 0.853

#: The rules: (number, window, points needed in it, distance from the centre in σ).
RULES: tuple[tuple[int, int, int, float], ...] = (
    (1, 1, 1, 3.0),
    (2, 3, 2, 2.0),
    (3, 5, 4, 1.0),
    (4, 8, 8, 0.0),
)


def western_electric(values: Sequence[float], centre: float, sigma: float) -> list[list[int]]:
    """For each of ``values`` (in time order), the rules (1–4) it completes.

    Nothing signals without spread (``sigma`` ≤ 0).
    """
    flags: list[list[int]] = [[] for _ in values]
    if not sigma > 0:
        return flags
    z = [(v - centre) / sigma for v in values]
    for rule, window, needed, beyond in RULES:
        for end in range(window - 1, len(z)):
            last = z[end]
            side = 1 if last > 0 else -1 if last < 0 else 0
            if side == 0 or abs(last) <= beyond:
                continue  # the point completing a pattern is itself part of it
            span = z[end - window + 1 : end + 1]
            if sum(side * x > beyond for x in span) >= needed:
                flags[end].append(rule)
    return flags


def moving_range_sigma(mr_bar: float) -> float:
    """σ of a moving range of two, from the mean moving range: d₃·MR̄/d₂."""
    return D3 * mr_bar / D2
