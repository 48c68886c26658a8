"""The accelerometer uncertainty budget's CPU per call, on units as the station sees them
(a budget is due at the end of every unit).

    python benchmarks/bench_budget_cpu.py                       # 20 units × 25 calls
    python benchmarks/bench_budget_cpu.py --units 5 --repeats 100

Each unit is drawn as the line meets them (:meth:`SensorTruth.draw`: datasheet spreads,
2 % cross-axis coupling) and taken through the ``kxm52-production`` plan as the station
takes it: the six poses of [Song2006] and the verification pose along their nominal
directions (as the virtual putter places them, so every pose lies within the coupling's
reach of its axis and the ``model`` term refits twice), each a window of the plan's
samples rounded by the ADC, the poses 10 s apart from power-up as the board warms (so
the ``temperature`` term is on, the poses' temperatures recorded as the putter reports
them). The budget is called as :func:`station.run.record.uncertainty_record` calls it,
each call timed with ``time.process_time`` after one call to warm up; printed: the
best and the median CPU per call over every unit's calls, and a digest of the budgets'
expanded uncertainties (the same digest before and after a change that keeps the
budget).
"""

import argparse
import hashlib
import statistics
import time

import numpy as np

from station.domain.calibration import solve
from station.domain.calibration.uncertainty import AccelerometerBudget, accelerometer_budget
from station.domain.sensors.sensor import ADC_MAX, ADC_MIN
from station.domain.signals.poses import POSES
from station.simulator.coverage import settings_of
from station.simulator.sensor import SensorTruth, Thermal

PROFILE = "kxm52-production"
#: Seconds between poses from power-up (the board warms by ~0.4 °C over the run).
POSE_INTERVAL_S = 10.0


def unit_call(rng: np.random.Generator) -> dict[str, object]:
    """One simulated unit's arguments to :func:`accelerometer_budget` (module docstring)."""
    settings = settings_of(PROFILE)
    names = (*settings.poses, settings.verification_pose)
    directions = np.array([POSES[name].gravity_body for name in names])
    samples = settings.stillness.window_samples
    fit = len(settings.poses)
    temperatures = Thermal().at(POSE_INTERVAL_S * np.arange(len(names), dtype=np.float64))
    truth = SensorTruth.draw(rng)
    clean = np.array(
        [
            truth.at(t).still_counts(u[None, :])[0]
            for t, u in zip(temperatures, directions, strict=True)
        ]
    )
    raw = clean[:, None, :] + rng.normal(0.0, truth.noise_counts, (len(names), samples, 3))
    counts = np.clip(np.rint(raw), ADC_MIN, ADC_MAX)
    means, spread = counts.mean(axis=1), counts.std(axis=1, ddof=1)
    return {
        "solution": solve(means[:fit], settings.model),
        "poses": means[:fit],
        "spread": spread[:fit],
        "samples": np.full(fit, samples),
        "verification": means[fit],
        "verification_spread": spread[fit],
        "verification_samples": samples,
        "temperatures": temperatures[:fit],
        "verification_temperature": float(temperatures[fit]),
    }


def digest(budgets: list[AccelerometerBudget]) -> str:
    """A short hash of every budget's terms, expanded uncertainties and verification
    ratio, bit for bit."""
    h = hashlib.sha256()
    for b in budgets:
        for values in b.terms.values():
            h.update(np.ascontiguousarray(values).tobytes())
        h.update(b.expanded.tobytes())
        h.update(np.float64(b.verification_ratio or 0.0).tobytes())
    return h.hexdigest()[:16]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=20, help="simulated units (default 20)")
    parser.add_argument("--repeats", type=int, default=25, help="calls per unit (default 25)")
    parser.add_argument("--seed", type=int, default=2028, help="random seed (default 2028)")
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    calls = [unit_call(rng) for _ in range(args.units)]
    budgets = [accelerometer_budget(**call) for call in calls]  # warm-up, and the digest
    times = []
    for call in calls:
        for _ in range(args.repeats):
            start = time.process_time()
            accelerometer_budget(**call)
            times.append(time.process_time() - start)
    print(
        f"{args.units} units × {args.repeats} calls: "
        f"best {1e3 * min(times):.2f} ms, median {1e3 * statistics.median(times):.2f} ms "
        f"CPU per call; budgets' digest {digest(budgets)}"
    )


if __name__ == "__main__":
    main()
