"""Monte Carlo validation of the uncertainty budget ([JCGM101]): does the truth lie within ±U?

    python benchmarks/bench_uncertainty.py               # 1,000 units a row (about 1 minute)
    python benchmarks/bench_uncertainty.py --units 200   # quicker
    python benchmarks/bench_uncertainty.py --only gyro-matrix   # K's table alone
    python benchmarks/bench_uncertainty.py --profile kxm52-production   # one profile's rows

For each limits profile (its shipped run plan: the six poses of [Song2006] and the
verification pose, or the whole unit's twelve with the nine-parameter model) and each
pose tilt (0: the poses exactly along their nominal directions, as the virtual putter
places them; 5: each pose off by up to 5°, as a hand places the putter in a cradle;
and 0° with the poses taken 10 s apart from power-up, the board warming by 0.43 °C over
the run, from units whose temperature coefficients lie anywhere within the datasheet's),
``--units`` simulated units with known truth (:mod:`station.simulator.coverage`) are
solved and their budgets computed as a run does. Prints a Markdown table: per coefficient
group, the fraction of coefficients whose truth lies within ±U (k = 2; target 93–97 %),
and the mean of |error|/U (0.40 for a normal error whose U is right).

Then the gyro matrix K of each profile: ``--units`` simulated units' streams, sample by
sample, through ``solve --stream``'s path with the profile's model
(:func:`station.simulator.coverage.simulate_gyro_matrix_coverage`); per element of K the
fraction within ±U and the mean |error|/U, with U as the budget gives it and, for
contrast, with the fit's standard errors alone (U = 2·SE, the budget before the moves'
geometry and the six-parameter model's coupling were added).
"""

import argparse
import time

import numpy as np

from station.domain.calibration import COVERAGE_FACTOR
from station.simulator.coverage import GROUPS, simulate_coverage, simulate_gyro_matrix_coverage

PROFILES = ("kxm52-production", "whole-unit")
#: Each profile's rows: the poses' tilt (degrees) and the seconds between poses from
#: power-up (None: every pose at the reference temperature).
ROWS = ((0.0, None), (5.0, None), (0.0, 10.0))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=1000, help="units per row (default 1000)")
    parser.add_argument("--seed", type=int, default=2025, help="random seed (default 2025)")
    parser.add_argument(
        "--only", choices=("coefficients", "gyro-matrix"), help="one of the two tables"
    )
    parser.add_argument("--profile", choices=PROFILES, help="one profile's rows (default both)")
    args = parser.parse_args()
    profiles = PROFILES if args.profile is None else (args.profile,)
    if args.only != "gyro-matrix":
        coefficients(args.units, args.seed, profiles)
    if args.only != "coefficients":
        gyro_matrix(args.units, args.seed, profiles)


def coefficients(units: int, seed: int, profiles: tuple[str, ...]) -> None:
    """The accelerometer's and gyro bias's table."""
    header = (
        "profile",
        "poses",
        "units",
        *(f"{g} within ±U" for g in GROUPS),
        "all",
        *(f"{g} mean \\|e\\|/U" for g in GROUPS),
        "time",
    )
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for profile in profiles:
        for tilt, interval in ROWS:
            start = time.perf_counter()
            c = simulate_coverage(profile, units, np.random.default_rng(seed), tilt, interval)
            elapsed = time.perf_counter() - start
            solved = units - c.refused
            cells = (
                profile,
                (f"≤ {tilt:g}°" if tilt else "0°")
                + ("" if interval is None else f", {interval:g} s apart from power-up"),
                f"{solved:,}" + (f" ({c.refused} refused)" if c.refused else ""),
                *(f"{100 * c.fraction(g):.1f} %" for g in GROUPS),
                f"{100 * c.fraction():.1f} %",
                *(f"{c.mean_ratio[g]:.2f}" for g in GROUPS),
                f"{elapsed:.0f} s",
            )
            print("| " + " | ".join(cells) + " |", flush=True)


def gyro_matrix(units: int, seed: int, profiles: tuple[str, ...]) -> None:
    """K's table: the budget's U, and the fit's standard errors alone."""
    import station.domain.gyro.motion.stream as stream

    budget = stream.gyro_matrix_uncertainty
    print()
    print(
        "| profile | U of K | units | within ±U: all | per element (rows x; y; z) "
        "| mean \\|e\\|/U | time |"
    )
    print("|---|---|---|---|---|---|---|")
    for profile in profiles:
        for name in ("budget", "fit's standard errors alone (2·SE)"):
            if name.startswith("fit"):
                stream.gyro_matrix_uncertainty = lambda fit, _: (
                    COVERAGE_FACTOR * fit.standard_errors
                )
            start = time.perf_counter()
            c = simulate_gyro_matrix_coverage(profile, units, np.random.default_rng(seed))
            elapsed = time.perf_counter() - start
            stream.gyro_matrix_uncertainty = budget
            rows = "; ".join(" ".join(f"{100 * v / c.units:.1f}" for v in row) for row in c.inside)
            cells = (
                profile,
                name,
                f"{c.units:,}" + (f" ({c.refused} refused)" if c.refused else ""),
                f"{100 * c.fraction():.1f} %",
                rows + " %",
                f"{c.mean_ratio.mean():.2f}",
                f"{elapsed:.0f} s",
            )
            print("| " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
