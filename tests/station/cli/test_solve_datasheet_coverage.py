"""The coverage of ``calstation solve``'s U on units the station's simulator did not make.

Units drawn from the datasheets alone (``tests/datasheet_units.py``, :class:`CoupledUnit`:
offsets, sensitivities and 2 % cross-axis coupling within the KXM52-1050's bounds, poses
held up to 5° off, each the mean of 1024 rounded noisy samples) are written as pose files
and solved by ``calstation solve --json`` with the six- and the nine-parameter model; the
truth of every offset and sensitivity must lie within its expanded U (k = 2) about 95 % of
the time ([JCGM100] 6.2; [JCGM101] 7.7).

Acceptance: the fraction of a group's coefficients (offsets or sensitivities: 3 per unit)
within ±U lies in the 99 % two-sided binomial band about 0.95 for that many coefficients,
``0.95 ± 2.576·√(0.95·0.05/n)`` (93.3–96.7 % for n = 450), the band of a U with exactly
95 % coverage; the coefficients of one unit are taken as independent, which their small
correlation (one fit) makes slightly optimistic.
"""

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from tests.conftest import CliRunner
from tests.datasheet_units import A12, AXIS_DIRECTIONS, TWELVE_DIRECTIONS, CoupledUnit

#: Units a model; 3 coefficients a group each.
UNITS = 150
#: The fixture's tilt of a pose off its nominal direction, degrees (at most).
TILT_DEG = 5.0
#: The coverage U claims, and the 99 % two-sided normal quantile of the band.
CLAIMED, Z99 = 0.95, 2.576
PLANS = {"six": AXIS_DIRECTIONS, "nine": TWELVE_DIRECTIONS}


@dataclass(frozen=True)
class Coverage:
    """Per group (``offset``, ``sensitivity``): the fraction of truths within ±U and the
    mean |error|/U (0.40 for a normal error whose U is right)."""

    within: dict[str, float]
    error_over_u: dict[str, float]
    count: int


def band(count: int) -> tuple[float, float]:
    """The 99 % binomial acceptance band of ``count`` coefficients about 95 %."""
    half = Z99 * np.sqrt(CLAIMED * (1 - CLAIMED) / count)
    return CLAIMED - half, CLAIMED + half


def coverage(call_cli: CliRunner, model: str, units: int, seed: int, into: Path) -> Coverage:
    """Solve ``units`` datasheet units' pose files with ``model``; count the truths in ±U."""
    rng = np.random.default_rng(seed)
    ratios: dict[str, list[float]] = {"offset": [], "sensitivity": []}
    for unit in range(units):
        truth = CoupledUnit.draw(rng, A12)
        path = truth.pose_file(rng, PLANS[model], TILT_DEG, into / f"{model}-{unit}.csv")
        result = call_cli("solve", str(path), "--model", model, "--json")
        assert result.returncode == 0, result.stderr
        data = json.loads(result.stdout)
        for group, true in (
            ("offset", truth.offset),
            ("sensitivity", truth.true_sensitivity(model)),
        ):
            value = np.array([data[group][a] for a in "xyz"])
            u = np.array([data["uncertainty"][group][a] for a in "xyz"])
            ratios[group] += list(np.abs(value - true) / u)
    return Coverage(
        within={g: float(np.mean(np.array(r) <= 1.0)) for g, r in ratios.items()},
        error_over_u={g: float(np.mean(r)) for g, r in ratios.items()},
        count=3 * units,
    )


@pytest.mark.parametrize(("model", "seed"), [("six", 61), ("nine", 62)])
def test_u_covers_the_truth_of_datasheet_units_about_95_percent_of_the_time(
    call_cli: CliRunner, tmp_path: Path, model: str, seed: int
) -> None:
    measured = coverage(call_cli, model, UNITS, seed, tmp_path)
    low, high = band(measured.count)
    for group, fraction in measured.within.items():
        assert low <= fraction <= high, (group, measured)
