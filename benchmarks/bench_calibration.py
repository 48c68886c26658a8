"""Calibration benchmarks: accuracy against the Cramér–Rao bound, the ±1 g jig, speed.

    python benchmarks/bench_calibration.py            # everything (about 2 minutes)
    python benchmarks/bench_calibration.py --quick    # fewer trials and units

(a) Monte Carlo RMS error of offsets and sensitivities (6-parameter model) against the
    Cramér–Rao bound for the same pose geometry and noise; efficiency = CRB / MSE.
(b) The classic ±1 g method against autocalibration when the jig is misplaced.
(c) Speed: one unit's solve, and the batch path (K × 6 poses) against a Python loop.
(d) Many poses: time and peak memory of one solve over 1e3, 1e4 and 1e5 poses (each in
    its own process, so its peak RSS is its own), and the robust fit on 12 poses with
    one bad pose.
"""

import argparse
import resource
import subprocess
import sys
import time

import numpy as np
from scipy.spatial.transform import Rotation

from station.domain.calibration import solve, solve_classic, solve_paper, solve_paper_batch
from station.simulator.recording import (
    pose_means,
    random_directions,
    six_directions,
    spread_directions,
)
from station.simulator.sensor import SensorTruth


def crb_six(unit: SensorTruth, directions: np.ndarray, sigma: float) -> np.ndarray:
    """Cramér–Rao bound (variances) of (o, s) for pose means a_i = o + diag(s)·u_i + n_i.

    n_i ~ N(0, σ²I); the unknown gravity directions u_i are nuisance parameters (two
    each, along a tangent basis). Returns the diagonal of the (o, s) block of the
    inverse Fisher information, counts².
    """
    n = len(directions)
    s = unit.sensitivity_counts_per_g
    jac = np.zeros((3 * n, 6 + 2 * n))
    for i, u in enumerate(directions):
        rows = slice(3 * i, 3 * i + 3)
        jac[rows, 0:3] = np.eye(3)
        jac[rows, 3:6] = np.diag(u)
        e1 = np.cross(u, [1.0, 0, 0] if abs(u[0]) < 0.9 else [0, 1.0, 0])
        e1 /= np.linalg.norm(e1)
        e2 = np.cross(u, e1)
        jac[rows, 6 + 2 * i] = s * e1
        jac[rows, 7 + 2 * i] = s * e2
    fisher = jac.T @ jac / sigma**2
    return np.diag(np.linalg.inv(fisher))[:6]


def table(*header: str) -> None:
    """Print a Markdown table header."""
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))


def row(*cells: object) -> None:
    """Print one Markdown table row."""
    print("| " + " | ".join(str(c) for c in cells) + " |")


def accuracy(trials: int, sigma: float) -> None:
    print(f"\n(a) accuracy vs Cramér–Rao bound, 6-parameter model, σ = {sigma} counts per pose")
    print(f"mean, {trials} trials per pose count")
    table(
        "poses",
        "method",
        "RMS offset err (counts)",
        "√CRB offset",
        "RMS sens err (counts/g)",
        "√CRB sens",
        "efficiency min / mean",
    )
    rng = np.random.default_rng(2026)
    for n in (6, 7, 9, 12, 18):
        unit = SensorTruth.draw_accelerometer(rng)
        directions = Rotation.random(random_state=n).apply(spread_directions(n))
        truth = np.concatenate([unit.offset_counts, unit.sensitivity_counts_per_g])
        errors = np.empty((trials, 6))
        for t in range(trials):
            sol = solve(pose_means(unit, directions, sigma, rng), "six")
            cal = sol.calibration
            errors[t] = np.concatenate([cal.offset, cal.sensitivity]) - truth
        mse = np.mean(errors**2, axis=0)
        crb = crb_six(unit, directions, sigma)
        eff = crb / mse
        method = "paper eq. 10" if n == 6 else "least squares"
        row(
            n,
            method,
            f"{np.sqrt(mse[:3].mean()):.4f}",
            f"{np.sqrt(crb[:3].mean()):.4f}",
            f"{np.sqrt(mse[3:].mean()):.4f}",
            f"{np.sqrt(crb[3:].mean()):.4f}",
            f"{eff.min():.3f} / {eff.mean():.3f}",
        )


def jig(units: int) -> None:
    print(f"\n(b) classic ±1 g vs autocalibration on a misplaced jig, {units} units, σ = 0.1")
    table(
        "jig error (deg)",
        "classic: mean abs offset err (counts)",
        "classic: mean abs sens err (%)",
        "autocal: mean abs offset err (counts)",
        "autocal: mean abs sens err (%)",
    )
    for tilt in (0.0, 2.0, 5.0, 10.0):
        rng = np.random.default_rng(7)
        c_off, c_sens, a_off, a_sens = [], [], [], []
        for _ in range(units):
            unit = SensorTruth.draw_accelerometer(rng)
            poses = pose_means(unit, six_directions(rng, tilt), 0.1, rng)
            classic = solve_classic(poses[0::2], poses[1::2])
            auto = solve_paper(poses).calibration
            c_off.append(np.abs(classic.offset - unit.offset_counts).mean())
            c_sens.append(
                np.abs(classic.sensitivity / unit.sensitivity_counts_per_g - 1).mean() * 100
            )
            a_off.append(np.abs(auto.offset - unit.offset_counts).mean())
            a_sens.append(np.abs(auto.sensitivity / unit.sensitivity_counts_per_g - 1).mean() * 100)
        row(
            f"{tilt:g}",
            f"{np.mean(c_off):.3f}",
            f"{np.mean(c_sens):.4f}",
            f"{np.mean(a_off):.3f}",
            f"{np.mean(a_sens):.4f}",
        )


def speed(batch_units: int) -> None:
    print("\n(c) speed (one core)")
    rng = np.random.default_rng(1)
    unit = SensorTruth.draw_accelerometer(rng, cross_axis=0.02)
    cases = [
        ("paper eq. 10, 6 poses", spread_directions(6), "six"),
        ("least squares six, 12 poses", spread_directions(12), "six"),
        ("least squares nine, 18 poses", spread_directions(18), "nine"),
    ]
    table("solve", "median time per unit")
    for name, directions, model in cases:
        poses = pose_means(unit, directions, 0.05, rng)
        times = []
        for _ in range(300):
            t0 = time.perf_counter()
            solve(poses, model)  # type: ignore[arg-type]
            times.append(time.perf_counter() - t0)
        row(name, f"{np.median(times) * 1e6:.0f} µs")

    offsets = 2048 + rng.uniform(-207, 207, (batch_units, 1, 3))
    sens = 819.2 * (1 + rng.uniform(-0.05, 0.05, (batch_units, 1, 3)))
    directions = six_directions(rng, 5.0)
    poses = offsets + directions[None] * sens + rng.normal(0, 0.05, (batch_units, 6, 3))
    rss0 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.perf_counter()
    batch = solve_paper_batch(poses)
    batch_s = time.perf_counter() - t0
    rss1 = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    loop_n = 3000
    t0 = time.perf_counter()
    for i in range(loop_n):
        solve_paper(poses[i])
    loop_rate = loop_n / (time.perf_counter() - t0)
    ok = int((batch.outcome == 0).sum())
    print()
    table("path", "units", "time", "units/s")
    rate = batch_units / batch_s
    row(
        "batch `solve_paper_batch`",
        f"{batch_units:,} ({ok:,} solved)",
        f"{batch_s:.2f} s",
        f"{rate:,.0f}",
    )
    row(
        "per-unit `solve_paper` loop",
        f"{loop_n:,}",
        f"{loop_n / loop_rate:.2f} s",
        f"{loop_rate:,.0f}",
    )
    print(
        f"\nbatch speed-up over the loop: {rate / loop_rate:.0f}×; "
        f"peak RSS growth during the batch: {(rss1 - rss0) / 1024:.0f} MiB"
    )


def one_size(n: int, model: str) -> None:
    """Solve n random poses of a coupled unit; print seconds and this process's peak RSS."""
    rng = np.random.default_rng(n)
    poses = pose_means(
        SensorTruth.draw_accelerometer(rng, cross_axis=0.02), random_directions(rng, n), 0.05, rng
    )
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    t0 = time.perf_counter()
    solution = solve(poses, model)  # type: ignore[arg-type]
    seconds = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(f"{seconds:.3f} {before / 1024:.0f} {peak / 1024:.0f} {len(solution.excluded)}")


def many_poses() -> None:
    print("\n(d) many poses: one solve, random directions, 2 % coupling, σ = 0.05 counts")
    table("poses", "model", "time", "peak RSS (MiB)", "RSS before the solve (MiB)")
    for n in (1_000, 10_000, 100_000):
        for model in ("six", "nine"):
            answer = subprocess.run(
                [sys.executable, __file__, "--one-size", str(n), "--model", model],
                capture_output=True,
                text=True,
                check=True,
            ).stdout.split()
            seconds, before, peak = float(answer[0]), answer[1], answer[2]
            row(f"{n:,}", model, f"{seconds:.2f} s", peak, before)
    rng = np.random.default_rng(12)
    found, trials = 0, 200
    for _ in range(trials):
        unit = SensorTruth.draw_accelerometer(rng, cross_axis=0.02)
        directions = Rotation.random(random_state=rng).apply(spread_directions(12))
        poses = pose_means(unit, directions, 0.05, rng)
        bad = int(rng.integers(12))
        poses[bad] += 100.0 * directions[bad]
        found += solve(poses, "nine").excluded == (bad,)
    print(f"\n100-count outlier on one of 12 poses (nine model): excluded {found}/{trials}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer trials and units")
    parser.add_argument("--one-size", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--model", default="six", help=argparse.SUPPRESS)
    parser.add_argument("--only-many", action="store_true", help="only (d), the many-pose rows")
    args = parser.parse_args()
    if args.one_size:
        one_size(args.one_size, args.model)
        return
    if not args.only_many:
        accuracy(trials=300 if args.quick else 2000, sigma=0.1)
        jig(units=100 if args.quick else 1000)
        speed(batch_units=100_000 if args.quick else 1_000_000)
    many_poses()


if __name__ == "__main__":
    main()
