"""Monte Carlo validation of the uncertainty budget ([JCGM101]): does the truth lie within ±U?

    python benchmarks/bench_uncertainty.py               # 1,000 units a row (about 1 minute)
    python benchmarks/bench_uncertainty.py --units 200   # quicker
    python benchmarks/bench_uncertainty.py --only gyro-matrix   # K's table alone

For each limits profile (its shipped run plan: the six poses of [Song2006] and the
verification pose, or the whole unit's twelve with the nine-parameter model) and each
pose tilt (0: the poses exactly along their nominal directions, as the virtual putter
places them; 5: each pose off by up to 5°, as a hand places the putter in a cradle),
``--units`` simulated units with known truth (:mod:`station.simulator.coverage`) are
solved and their budgets computed as a run does. Prints a Markdown table: per coefficient
group, the fraction of coefficients whose truth lies within ±U (k = 2; target 93–97 %),
and the mean of |error|/U (0.40 for a normal error whose U is right).

Then the gyro matrix K of the whole-unit profile: ``--units`` simulated whole units'
streams, sample by sample, through ``solve --stream``'s path
(:func:`station.simulator.coverage.simulate_gyro_matrix_coverage`); per element of K the
fraction within ±U and the mean |error|/U, with U as the budget gives it and, for
contrast, with the fit's standard errors alone (U = 2·SE, the budget before the moves'
geometry was added).
"""

import argparse
import time

import numpy as np

from station.domain.calibration import COVERAGE_FACTOR
from station.simulator.coverage import GROUPS, simulate_coverage, simulate_gyro_matrix_coverage

PROFILES = ("kxm52-production", "whole-unit")
TILTS_DEG = (0.0, 5.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=1000, help="units per row (default 1000)")
    parser.add_argument("--seed", type=int, default=2025, help="random seed (default 2025)")
    parser.add_argument(
        "--only", choices=("coefficients", "gyro-matrix"), help="one of the two tables"
    )
    args = parser.parse_args()
    if args.only != "gyro-matrix":
        coefficients(args.units, args.seed)
    if args.only != "coefficients":
        gyro_matrix(args.units, args.seed)


def coefficients(units: int, seed: int) -> None:
    """The accelerometer's and gyro bias's table."""
    header = (
        "profile",
        "pose tilt",
        "units",
        *(f"{g} within ±U" for g in GROUPS),
        "all",
        *(f"{g} mean \\|e\\|/U" for g in GROUPS),
        "time",
    )
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for profile in PROFILES:
        for tilt in TILTS_DEG:
            start = time.perf_counter()
            c = simulate_coverage(profile, units, np.random.default_rng(seed), tilt)
            elapsed = time.perf_counter() - start
            solved = units - c.refused
            cells = (
                profile,
                f"≤ {tilt:g}°",
                f"{solved:,}" + (f" ({c.refused} refused)" if c.refused else ""),
                *(f"{100 * c.fraction(g):.1f} %" for g in GROUPS),
                f"{100 * c.fraction():.1f} %",
                *(f"{c.mean_ratio[g]:.2f}" for g in GROUPS),
                f"{elapsed:.0f} s",
            )
            print("| " + " | ".join(cells) + " |", flush=True)


def gyro_matrix(units: int, seed: int) -> None:
    """K's table: the budget's U, and the fit's standard errors alone."""
    import station.domain.gyro.motion.stream as stream

    budget = stream.gyro_matrix_uncertainty
    print()
    print(
        "| U of K | units | within ±U: all | per element (rows x; y; z) | mean \\|e\\|/U | time |"
    )
    print("|---|---|---|---|---|---|")
    for name in ("budget (fit + moves' geometry)", "fit's standard errors alone (2·SE)"):
        if name.startswith("fit"):
            stream.gyro_matrix_uncertainty = lambda fit, _: COVERAGE_FACTOR * fit.standard_errors
        start = time.perf_counter()
        c = simulate_gyro_matrix_coverage("whole-unit", units, np.random.default_rng(seed))
        elapsed = time.perf_counter() - start
        stream.gyro_matrix_uncertainty = budget
        rows = "; ".join(" ".join(f"{100 * v / c.units:.1f}" for v in row) for row in c.inside)
        cells = (
            name,
            f"{c.units:,}",
            f"{100 * c.fraction():.1f} %",
            rows + " %",
            f"{c.mean_ratio.mean():.2f}",
            f"{elapsed:.0f} s",
        )
        print("| " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
