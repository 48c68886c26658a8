"""How large the 1 g g-sensitivity term of [Park2014]_ is in the gyro matrix K.

    python benchmarks/bench_k_g_sensitivity.py [--units 200]

The gyros' scale factor changes with the specific force along each gyro's sense axis
(about ±600 ppm/g, :mod:`station.simulator.sensor`). On the line that force is gravity,
1 g, and it turns with the unit: during the whole-unit plan's moves it acts as an
orientation-dependent scale error that no constant K can hold. This measures what it
does to K when it is not removed: for each simulated unit (random signs, magnitudes
600 ppm/g ± 5 %) the moves of the shipped whole-unit plan (the simulator's minimum-jerk
1.5 s turns, 500 samples/s) are generated with a perfect gyro triad (K = I, no bias, no
noise) apart from that term, and K is fitted (:func:`station.domain.gyro.motion.fit_gyro_matrix`)
against the exact gravity directions. Every ppm of K − I is the term's doing. With the
term removed first (as the station does when a fit is stored) K comes out I to the
integration's precision.
"""

import argparse
import itertools

import numpy as np
from scipy.spatial.transform import Rotation

from station.domain.gyro import GyroErrorModel, compensate
from station.domain.gyro.motion import Move, fit_gyro_matrix, integrate_rates
from station.domain.signals.poses import pose
from station.loop.config import load_config
from station.simulator.motion import Handling, MotionModel
from station.simulator.sensor import GYRO_G_SENSITIVITY_PER_G, GYRO_SENSE_AXIS

RATE_HZ = 500.0
MOVE_S = 1.5
STILL_S = 0.5


def move_samples(start: str, end: str, rng: np.random.Generator) -> tuple[np.ndarray, ...]:
    """Times, true rates (deg/s) and specific force (g) of one move with still ends."""
    motion = MotionModel(
        pose(start).rotation, rng, Handling(tremor_rock_deg=0.0, tremor_shake_g=0.0)
    )
    motion.move_to(pose(end).rotation, STILL_S, MOVE_S)
    t = np.arange(int((2 * STILL_S + MOVE_S) * RATE_HZ)) / RATE_HZ
    kinematics = motion.evaluate(t)
    return t, kinematics.rate_dps, kinematics.force_g


def n_matrix(g_per_g: np.ndarray) -> np.ndarray:
    n = np.zeros((3, 3))
    for gyro, sense in enumerate(GYRO_SENSE_AXIS):
        n[gyro, sense] = g_per_g[gyro]
    return n


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--units", type=int, default=200)
    args = parser.parse_args()
    run = load_config(None, {"limits_profile": "whole-unit"}).run
    names = [*run.poses, run.verification_pose]
    rng = np.random.default_rng(17)
    pairs = list(itertools.pairwise(names))
    samples = [move_samples(a, b, rng) for a, b in pairs]
    last = move_samples(run.verification_pose, run.gyro_verification_pose, rng)
    errors, removed, verify = [], [], []
    for _ in range(args.units):
        g = GYRO_G_SENSITIVITY_PER_G * rng.uniform(0.95, 1.05, 3) * rng.choice([-1.0, 1.0], 3)
        n = n_matrix(g)
        term = GyroErrorModel(np.zeros(3), np.eye(3), np.zeros((3, 3)), n)
        plain, compensated = [], []
        for (a, b), (t, rate, force) in zip(pairs, samples, strict=True):
            measured = rate + (force @ n.T) * rate
            ends = (pose(a).gravity_body, pose(b).gravity_body)
            plain.append(Move(t, measured, *ends))
            compensated.append(Move(t, compensate(term, measured, force), *ends))
        errors.append(fit_gyro_matrix(plain, np.zeros(3)).scale_matrix - np.eye(3))
        removed.append(fit_gyro_matrix(compensated, np.zeros(3)).scale_matrix - np.eye(3))
        t, rate, force = last
        rotation: Rotation = integrate_rates(t, np.radians(rate + (force @ n.T) * rate))
        u0 = pose(run.verification_pose).gravity_body
        u1 = pose(run.gyro_verification_pose).gravity_body
        verify.append(np.degrees(np.arccos(np.clip(rotation.apply(u1) @ u0, -1, 1))))
    e, r = np.abs(errors) * 1e6, np.abs(removed) * 1e6
    print(f"{args.units} units, the whole-unit plan's {len(pairs)} moves")
    print(
        f"K − I with the 1 g term left in, ppm: rms {np.sqrt((e**2).mean()):.0f}, "
        f"largest element {e.max():.0f}"
    )
    print("  rms per element, ppm:")
    for row in np.sqrt((e**2).mean(axis=0)):
        print("   " + " ".join(f"{v:6.0f}" for v in row))
    print(f"K − I with the term removed first, ppm: largest element {r.max():.1f}")
    print(
        f"verification move (K = I otherwise), degrees: mean {np.mean(verify):.4f}, "
        f"largest {np.max(verify):.4f}"
    )


if __name__ == "__main__":
    main()
