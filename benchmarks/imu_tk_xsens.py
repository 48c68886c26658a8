"""Convert imu_tk's Xsens test recording into a ``calstation solve --stream`` log.

imu_tk (Tedaldi, Pretto, Menegatti; BSD licence per its README) ships, in
``bin/test_data/``, the raw recording of its own procedure: ``xsens_acc.mat`` and
``xsens_gyro.mat``, text columns ``t ax ay az`` and ``t gx gy gz`` at 100 samples/s,
both 16-bit raw counts. Its example (``apps/test_imu_calib.cpp``) takes the accelerometer
zero at 32768 counts, the gyros at 1/6258 rad/s per count, and the first 50 s as the
initial static interval from which the gyro bias is taken. The mapping to the putter's
log:

- accelerometer: ``a12 = 2048 + (a16 − 32768) · 819.2 / G``, with G = 3723.7 counts/g,
  the norm of the mean reading over the first 50 s about 32768. An affine change of
  units, which the accelerometer models absorb (offsets and sensitivities change,
  the gravity directions do not); it only puts the readings where the station's
  stillness judge expects 12-bit counts (2048 at 0 g, 819.2 counts/g).
- gyros: ``g_dps = (g16 − m50) / 6258 · 180/π``, m50 the mean over the first 50 s
  (as imu_tk does). Without it the y and z gyros read −2.8 and −2.4 deg/s at rest,
  above the stillness judge's 1 deg/s; ``calstation solve`` then fits what bias is left.

Run: ``python benchmarks/imu_tk_xsens.py OUT.csv [--repo GIT_DIR]`` (the repository's git
directory, by default the fetched mirror). It writes the log, then reports what
``calstation solve OUT.csv --stream`` finds with each accelerometer model, and a
held-out check: K fitted on the even-numbered moves alone, the residuals of the odd ones.
"""

import argparse
import io
import subprocess
from pathlib import Path

import numpy as np

from station.domain.calibration import Model
from station.domain.gyro.motion import Move, calibrate_stream, fit_gyro_matrix, integrate_rates
from station.domain.gyro.motion.matrix_fit import GyroMatrixFit
from station.domain.gyro.motion.stream_file import read_stream_file

MIRROR = Path("/work/.mirror/Kyle-ak+imu_tk/repo")
ACC_ZERO = 32768.0
ACC_COUNTS_PER_G = 3723.7
GYRO_COUNTS_PER_RAD_S = 6258.0
INITIAL_STATIC_S = 50.0
PUTTER_ZERO = 2048.0
PUTTER_COUNTS_PER_G = 819.2


def load(repo: Path, name: str) -> np.ndarray:
    """A ``bin/test_data`` file of the repository, as a float array."""
    text = subprocess.run(
        ["git", "-C", str(repo), "show", f"HEAD:bin/test_data/{name}"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    return np.loadtxt(io.StringIO(text))


def convert(acc: np.ndarray, gyro: np.ndarray) -> np.ndarray:
    """Rows ``t, ax, ay, az, gx, gy, gz`` in the putter log's units."""
    if not np.array_equal(acc[:, 0], gyro[:, 0]):
        raise SystemExit("accelerometer and gyro files have different time stamps")
    t = acc[:, 0]
    initial = t < t[0] + INITIAL_STATIC_S
    a12 = PUTTER_ZERO + (acc[:, 1:] - ACC_ZERO) * (PUTTER_COUNTS_PER_G / ACC_COUNTS_PER_G)
    bias16 = gyro[initial, 1:].mean(axis=0)
    dps = np.degrees((gyro[:, 1:] - bias16) / GYRO_COUNTS_PER_RAD_S)
    return np.column_stack([t, a12, dps])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--repo", type=Path, default=MIRROR)
    args = parser.parse_args()
    rows = convert(load(args.repo, "xsens_acc.mat"), load(args.repo, "xsens_gyro.mat"))
    np.savetxt(args.out, rows, delimiter=",", header="t,ax,ay,az,gx,gy,gz", comments="", fmt="%.6f")
    print(f"{args.out}: {len(rows)} samples over {rows[-1, 0] - rows[0, 0]:.1f} s")
    stream = read_stream_file(args.out)
    models: tuple[Model, ...] = ("six", "nine")
    for model in models:
        result = calibrate_stream(stream, model)
        gyro = result.gyro
        print(
            f"{model}: {len(result.stills)} stills, accel rms "
            f"{result.accel.quality.residual_rms_mg:.3f} mg, "
            f"bias left {np.round(result.bias_dps, 4).tolist()} deg/s"
        )
        _residuals("  all moves", gyro)
        print("  K =", np.array2string(gyro.scale_matrix, precision=5).replace("\n", ""))
        se = gyro.standard_errors
        if se is not None:
            print("  σ(K) =", np.array2string(se, precision=5).replace("\n", ""))
        even = [m for i, m in enumerate(result.moves) if i % 2 == 0]
        odd = [m for i, m in enumerate(result.moves) if i % 2 == 1]
        half = fit_gyro_matrix(even, result.bias_dps)
        check = fit_gyro_matrix(odd, result.bias_dps)
        change = np.abs(half.scale_matrix - gyro.scale_matrix).max()
        print(f"  K from even moves − K from all: max {change:.5f}")
        held = _held_out(odd, half, result.bias_dps)
        print(
            f"  odd moves with K from even moves: rms {np.sqrt(np.mean(held**2)):.3f}°,"
            f" max {held.max():.3f}° (fitted on themselves: rms {check.residual_rms_deg:.3f}°)"
        )


def _residuals(label: str, gyro: GyroMatrixFit) -> None:
    ident, fitted = gyro.residual_identity_deg, gyro.residual_deg
    print(
        f"{label}: {len(gyro.used)} used, {len(gyro.unusable)} unusable; residual with K = I: "
        f"median {np.median(ident):.2f}°, max {ident.max():.2f}°; with K: rms "
        f"{gyro.residual_rms_deg:.3f}°, median {np.median(fitted):.3f}°, max {fitted.max():.3f}°"
    )


def _held_out(moves: list[Move], fit: GyroMatrixFit, bias: np.ndarray) -> np.ndarray:
    """Residuals (deg) of ``moves`` under ``fit``'s K, which did not see them."""
    k_inv_t = np.linalg.inv(fit.scale_matrix).T
    out = []
    for m in moves:
        rotation = integrate_rates(m.t, np.radians(m.rates_dps - bias) @ k_inv_t)
        cos = np.clip(rotation.apply(m.gravity_after) @ m.gravity_before, -1.0, 1.0)
        out.append(np.degrees(np.arccos(cos)))
    return np.array(out)


if __name__ == "__main__":
    main()
