"""Five real MPU-9150s (mikoff/imu-calib's public recordings), calibrated by the station
and compared with the calibration their repository publishes.

    python benchmarks/mikoff_mpu9150.py

The recordings (``tests/data/mikoff/``, MIT: five InvenSense MPU-9150s turned by hand
through 21–25 still poses each, m/s² and rad/s at 100 samples/s, no time column) are read
by ``calstation solve LOG --stream --model nine --accel-units m/s2 --gyro-units rads
--rate 100 --json``, a real process each. Printed per unit and axis: the accelerometer
offset (m/s²) and scale, the gyro bias (rad/s) and K's diagonal, each with its U (k = 2),
beside the published figure (``images/real_imu.png`` of the repository: their scale
against 9.81 m/s², restated against g₀ here; their gyro bias in deg/s, shown in rad/s),
and whether the difference lies within U plus the published figure's rounding. Their
gyro model, ``ω_meas = R(ε)ᵀ·(M·ω + b)`` with M upper triangular, has K's diagonal
``1 + s`` to first order in its small angles; its off-diagonal terms are in another
parametrisation and are not compared.
"""

import gzip
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the published figures live beside the test that checks them
from tests.station.cli.test_solve_mpu9150 import (  # noqa: E402
    DATA,
    DECLARED,
    G0,
    HEADER,
    PUBLISHED_ACCEL_BIAS,
    PUBLISHED_ACCEL_SCALE_PCT,
    PUBLISHED_GYRO_BIAS_DPS,
    ROUNDING,
    THEIR_G,
)

#: The published gyro scale s (%) of units #1…#5 (images/real_imu.png).
PUBLISHED_GYRO_SCALE_PCT = np.array(
    [
        [0.041, 0.457, 0.826],
        [0.007, 0.26, -0.179],
        [-0.058, 0.277, 0.242],
        [0.227, 0.599, 0.308],
        [0.226, 0.57, 0.853],
    ]
)


def solved(unit: int, into: Path) -> dict[str, object]:
    """``calstation solve --stream --json`` of unit ``unit``'s recording, as a process."""
    with gzip.open(DATA / f"imu{unit}.log.gz", "rt") as src:
        table = np.loadtxt(src)
    path = into / f"imu{unit}.csv"
    rows = np.column_stack([np.arange(len(table)), table])
    np.savetxt(path, rows, delimiter=",", header=HEADER, comments="", fmt="%.17g")
    calstation = Path(sys.executable).parent / "calstation"
    command = [str(calstation), "solve", str(path), "--stream", "--model", "nine", "--json"]
    done = subprocess.run([*command, *DECLARED], capture_output=True, text=True, check=True)
    data: dict[str, object] = json.loads(done.stdout)
    return data


def main() -> None:
    within = {"offset": 0, "scale": 0, "gyro bias": 0, "K diagonal": 0}
    with tempfile.TemporaryDirectory() as tmp:
        for unit in range(5):
            data: dict[str, object] = solved(unit, Path(tmp))
            u: dict[str, object] = data["uncertainty"]  # type: ignore[assignment]
            gyro: dict[str, object] = data["gyro"]  # type: ignore[assignment]
            xyz = lambda d: np.array([d[a] for a in "xyz"])  # noqa: E731
            rows = {
                "offset": (
                    xyz(data["offset"]),
                    xyz(u["offset"]),
                    PUBLISHED_ACCEL_BIAS[unit],
                    ROUNDING["bias"],
                ),
                "scale": (
                    xyz(data["sensitivity"]) * G0 / THEIR_G,
                    xyz(u["sensitivity"]),
                    1 + PUBLISHED_ACCEL_SCALE_PCT[unit] / 100,
                    ROUNDING["scale"],
                ),
                "gyro bias": (
                    np.array(gyro["bias"]),
                    np.array(u["gyro_bias"]),
                    np.radians(PUBLISHED_GYRO_BIAS_DPS[unit]),
                    ROUNDING["gyro"],
                ),
                "K diagonal": (
                    np.diag(np.array(gyro["scale_matrix"])),
                    np.diag(np.array(u["gyro_matrix"])),
                    1 + PUBLISHED_GYRO_SCALE_PCT[unit] / 100,
                    ROUNDING["scale"],
                ),
            }
            print(f"unit #{unit + 1} ({data['poses']} still poses), units {data['units']}")
            for name, (ours, big_u, theirs, rounding) in rows.items():
                ok = np.abs(ours - theirs) <= big_u + rounding
                within[name] += int(ok.sum())
                shown = "  ".join(
                    f"{o:+.5f}±{v:.5f} vs {t:+.5f}{'' if k else ' OUTSIDE'}"
                    for o, v, t, k in zip(ours, big_u, theirs, ok, strict=True)
                )
                print(f"  {name:10s} {shown}")
    print("within U and the published rounding, of 15:", within)


if __name__ == "__main__":
    main()
