"""One bad pose among 8-12: how often the fit excludes it, refuses, or excludes another.

    python benchmarks/bench_exclusion.py                     # 6,000 cap-shaped sets, then
                                                             # 3,000 over the sphere (~40 s)
    python benchmarks/bench_exclusion.py --sets 500

Simulation with known truth (``docs/calibration.md``, *Consistency*): a unit without
cross-axis coupling (the six-parameter model holds), N pose directions, each pose mean
with 0.05 counts of noise, and one pose moved 40-400 counts along gravity (either way).
``cap``: N = 8-10 directions within 40-90° of one direction, then turned at random: the
narrow sets on which a good pose's refit can absorb the bad one. ``sphere``: N = 8-12
directions anywhere. Each set is solved with the six-parameter model
(:func:`station.domain.calibration.solve`) and counted as *right* (the bad pose
excluded), *wrong* (another pose excluded: a wrong calibration), *refused* (an
inconsistent set, or another refusal: geometry, datasheet) or *not seen* (the set passed
whole). Seeded: the same counts every run.
"""

import argparse
from collections import Counter

import numpy as np
from scipy.spatial.transform import Rotation

from station.domain.calibration import CalibrationError, InconsistentPosesError, solve
from station.simulator.recording import pose_means
from station.simulator.sensor import SensorTruth

NOISE = 0.05
SHAPES = {"cap": (8, 10), "sphere": (8, 12)}


def directions(rng: np.random.Generator, n: int, shape: str, seed: int) -> np.ndarray:
    """``n`` unit vectors: within a random 40-90° cap (``cap``) or anywhere (``sphere``)."""
    cap = np.radians(rng.uniform(40.0, 90.0)) if shape == "cap" else np.pi
    found: list[np.ndarray] = []
    while len(found) < n:
        d = rng.standard_normal(3)
        d /= np.linalg.norm(d)
        if np.arccos(d[2]) <= cap:
            found.append(d)
    return Rotation.random(random_state=seed).apply(np.array(found))


def outcome(seed: int, shape: str) -> str:
    """What the solve makes of one seeded set with one bad pose."""
    rng = np.random.default_rng(seed)
    low, high = SHAPES[shape]
    n = int(rng.integers(low, high + 1))
    where = directions(rng, n, shape, seed)
    drawn = SensorTruth.draw_accelerometer(rng, cross_axis=0.0)
    unit = SensorTruth.accelerometer(drawn.offset_counts, np.diag(drawn.sensitivity_counts_per_g))
    poses = pose_means(unit, where, NOISE, rng)
    bad = int(rng.integers(0, n))
    poses[bad] += rng.uniform(40.0, 400.0) * rng.choice([-1.0, 1.0]) * where[bad]
    try:
        excluded = solve(poses, "six").excluded
    except InconsistentPosesError:
        return "refused: inconsistent"
    except CalibrationError:
        return "refused: other"
    if not excluded:
        return "not seen"
    return "right" if excluded == (bad,) else "WRONG"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sets", type=int, default=None, help="sets per shape")
    parser.add_argument("--shape", choices=sorted(SHAPES), nargs="+", default=["cap", "sphere"])
    args = parser.parse_args()
    print("| shape | sets | right | wrong | refused: inconsistent | refused: other | not seen |")
    print("|---|---|---|---|---|---|---|")
    for shape in args.shape:
        sets = args.sets or (6000 if shape == "cap" else 3000)
        counts = Counter(outcome(seed, shape) for seed in range(sets))
        print(
            f"| {shape} | {sets} | {counts['right']} | {counts['WRONG']} "
            f"| {counts['refused: inconsistent']} | {counts['refused: other']} "
            f"| {counts['not seen']} |"
        )


if __name__ == "__main__":
    main()
