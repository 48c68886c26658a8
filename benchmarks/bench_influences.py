"""The influences U carries, each against the budget without it: coverage of ±U (k = 2).

    python benchmarks/bench_influences.py                 # 200-250 units a row (minutes)
    python benchmarks/bench_influences.py --units 50

Simulation with known truth (:func:`station.simulator.coverage.simulate_coverage`,
``docs/calibration.md``, the uncertainty budget), seeded: the same figures every run.
Each row is one influence, measured with the budget as it is and with the budget that
leaves it out (the baseline of the same run):

- ``knock``: a 1 s knock of 0.02 g inside one of the six poses (seed 43): the pose's
  spread above the noise widens its mean's variance
  (:data:`~station.domain.calibration.uncertainty.DISTURBED_SPREAD_RATIO`), against a
  budget that never marks a pose disturbed;
- ``cross-axis``: units coupled within ±1 % (5° tilt, seed 44), the coupling declared
  at 1 %, against the KXM52's 2 % assumed for every sensor;
- ``gyro-bias``: a gyro bias moving 0.05 deg/s between power-ons (seed 45), that
  repeatability declared, against none declared.
"""

import argparse
from collections.abc import Callable
from typing import Any

import numpy as np

import station.domain.calibration.uncertainty as uncertainty
import station.simulator.coverage as coverage
from station.simulator.coverage import GROUPS, Coverage, simulate_coverage


def _row(name: str, result: Coverage, groups: tuple[str, ...] = GROUPS) -> str:
    figures = ", ".join(
        f"{g} {result.fraction(g):.1%} (|e|/U {result.mean_ratio[g]:.2f})" for g in groups
    )
    return f"{name}: {figures}; refused {result.refused}"


def _without(module: Any, name: str, value: object, run: Callable[[], Coverage]) -> Coverage:
    """``run()`` with ``module.name`` set to ``value`` (the budget without an influence)."""
    kept = getattr(module, name)
    setattr(module, name, value)
    try:
        return run()
    finally:
        setattr(module, name, kept)


def knock(units: int) -> None:
    def run() -> Coverage:
        return simulate_coverage(
            "kxm52-production", units, np.random.default_rng(43), 0.0, knock_g=0.02, knock_s=1.0
        )

    print(_row("knock, disturbed pose in U", run()))
    print(_row("knock, baseline", _without(uncertainty, "DISTURBED_SPREAD_RATIO", np.inf, run)))


def cross_axis(units: int) -> None:
    def run() -> Coverage:
        rng = np.random.default_rng(44)
        return simulate_coverage("kxm52-production", units, rng, 5.0, cross_axis=0.01)

    print(_row("cross-axis 1 % declared", run()))
    budget = coverage.accelerometer_budget

    def assumed(*args: Any, **kwargs: Any) -> Any:
        return budget(*args, **{**kwargs, "cross_axis_bound": 0.02})

    print(
        _row(
            "cross-axis, baseline 2 % assumed",
            _without(coverage, "accelerometer_budget", assumed, run),
        )
    )


def gyro_bias(units: int) -> None:
    for declared in (True, False):
        result = simulate_coverage(
            "kxm52-production",
            units,
            np.random.default_rng(45),
            0.0,
            gyro_turn_on_dps=0.05,
            declare_turn_on=declared,
        )
        name = "gyro-bias repeatability declared" if declared else "gyro-bias, baseline none"
        print(_row(name, result, ("gyro_bias",)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=None, help="units a row")
    args = parser.parse_args()
    knock(args.units or 200)
    cross_axis(args.units or 250)
    gyro_bias(args.units or 250)


if __name__ == "__main__":
    main()
