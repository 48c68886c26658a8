"""imucal's example Ferraris session, calibrated by the station and by imucal itself.

    git clone https://github.com/mad-lab-fau/imucal /tmp/imucal   # the public recording
    pip install 'imucal>=2.6,<3'                                    # imucal itself
    python benchmarks/imucal_ferraris.py /tmp/imucal

The recording (``example_data/example_ferraris_session.csv`` of mad-lab-fau/imucal) is a
6-DOF IMU put through Ferraris' procedure at 102.4 samples/s: six still faces, then a
turn of 360° about each axis; the accelerometer in m/s², the gyros in deg/s. Nobody here
made it. The station reads it as any IMU's recording, with its units declared
(``calstation solve LOG --stream --accel-units m/s2 --rate 102.4``, and with
``--known-turn-deg 360`` its three whole turns declared): its own stillness
judge finds the still poses, the six-parameter model ([Song2006]) is fitted to them by
least squares and the gyro bias and matrix K come from the moves between them
([Tedaldi2014]). imucal's ``FerrarisCalibration`` is given the session's annotated
regions (``example_ferraris_session_list.json``, shipped beside it), as its own example
does. Printed: each axis' accelerometer bias (mg) and scale, and each gyro's bias (deg/s)
and scale, by both, and the differences; and each still-to-still move the station found,
held out, predicted by the station's K fitted on the others and by imucal's calibration
(:func:`held_out`), with both RMS side by side. imucal also fits the accelerometer's
misalignment, which the six-parameter model leaves out (its nine-parameter model needs
poses off the axes, which a Ferraris session does not have: it is refused, as it should
be).
"""

import argparse
import csv
import json
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from station.domain.gyro.motion import (
    StreamCalibration,
    calibrate_stream,
    fit_gyro_matrix,
    integrate_rates,
    stream_thresholds,
)
from station.domain.gyro.motion.stream_file import read_stream_file
from station.domain.gyro.motion.stream_units import StreamUnits, check_units, convert
from station.domain.sensors.sensor import NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G

RATE_HZ = 102.4
#: Standard gravity, m/s² (the unit conversion the station declares, stream_units.py).
G0 = 9.80665
SESSION = Path("example_data") / "example_ferraris_session.csv"
REGIONS = Path("example_data") / "example_ferraris_session_list.json"


def as_station_stream(session: Path, into: Path) -> Path:
    """The session's columns under the station's names (``t,ax,ay,az,gx,gy,gz``)."""
    path = into / "ferraris_stream.csv"
    with session.open(newline="") as src, path.open("w", newline="") as dst:
        writer = csv.writer(dst)
        writer.writerow(["t", "ax", "ay", "az", "gx", "gy", "gz"])
        for row in csv.DictReader(src):
            writer.writerow(
                [int(row["n_samples"]) / RATE_HZ]
                + [row[f"acc_{a}"] for a in "xyz"]
                + [row[f"gyr_{a}"] for a in "xyz"]
            )
    return path


def station(stream_csv: Path, known_turn_deg: float | None) -> dict[str, Any]:
    """The station's calibration of the stream, in imucal's terms (m/s², deg/s), and
    ``"result"``, the calibration itself."""
    units = StreamUnits(accel="m/s2", rate_hz=RATE_HZ)
    stream = convert(read_stream_file(stream_csv), units)
    check_units(stream, units)
    result = calibrate_stream(
        stream,
        "six",
        thresholds=stream_thresholds(stream.rate_hz, 1.0),
        known_turn_deg=known_turn_deg,
    )
    document = result.to_dict()
    offset = np.array([document["offset"][a] for a in "xyz"])
    sensitivity = np.array([document["sensitivity"][a] for a in "xyz"])
    gyro = document["gyro"]
    return {
        "acc_bias_ms2": (offset - NOMINAL_OFFSET_COUNTS) / NOMINAL_SENSITIVITY_COUNTS_PER_G * G0,
        "acc_scale": sensitivity / NOMINAL_SENSITIVITY_COUNTS_PER_G,
        "gyr_bias_dps": np.array(gyro["bias_dps"]),
        "gyr_scale": np.diag(np.array(gyro["scale_matrix"])),
        "poses": document["poses"],
        "moves": gyro["moves"],
        "turns_deg": gyro["known_turn_swept_deg"],
        "result": result,
    }


def imucal(repo: Path) -> dict[str, Any]:
    """imucal's Ferraris calibration of the session, over its annotated regions, and
    ``"calibrated"``: the whole session's accelerometer (m/s²) and gyros (deg/s) as that
    calibration corrects them (misalignment and the gyros' g-dependence included)."""
    import pandas as pd
    from imucal import FerrarisCalibration, ferraris_regions_from_section_list

    data = pd.read_csv(repo / SESSION, header=0, index_col=0)
    sections = pd.read_json(repo / REGIONS).T
    regions = ferraris_regions_from_section_list(data, sections)
    info = FerrarisCalibration().compute(
        regions, sampling_rate_hz=RATE_HZ, from_acc_unit="m/s^2", from_gyr_unit="deg/s"
    )
    acc, gyr = info.calibrate(
        data[[f"acc_{a}" for a in "xyz"]].to_numpy(dtype=float),
        data[[f"gyr_{a}" for a in "xyz"]].to_numpy(dtype=float),
        acc_unit="m/s^2",
        gyr_unit="deg/s",
    )
    return {
        "calibrated": (np.asarray(acc, dtype=float), np.asarray(gyr, dtype=float)),
        "acc_bias_ms2": np.asarray(info.b_a, dtype=float),
        "acc_scale": np.diag(np.asarray(info.K_a, dtype=float)),
        "gyr_bias_dps": np.asarray(info.b_g, dtype=float),
        "gyr_scale": np.diag(np.asarray(info.K_g, dtype=float)),
    }


def move_residual_deg(
    t: np.ndarray, rates_dps: np.ndarray, before: np.ndarray, after: np.ndarray
) -> float:
    """How far, degrees, the corrected rates (n, 3) integrated over a move carry the
    gravity direction after it from the one before it ([Tedaldi2014]'s residual)."""
    rotation = integrate_rates(t, np.radians(rates_dps))
    after, before = after / np.linalg.norm(after), before / np.linalg.norm(before)
    return float(np.degrees(np.arccos(np.clip(rotation.apply(after) @ before, -1.0, 1.0))))


def held_out(
    ours: StreamCalibration, theirs: tuple[np.ndarray, np.ndarray], known_turn_deg: float | None
) -> tuple[np.ndarray, np.ndarray]:
    """Residuals (deg) of each still-to-still move the station found, held out: with the
    station's K fitted on the other moves alone (leave one out), and with imucal's
    calibration, which never saw the flips between faces (its regions are the stills and
    the turns), over the same samples, its gravity directions from its corrected stills."""
    acc, gyr = theirs
    station_deg, imucal_deg = [], []
    for i, move in enumerate(ours.moves):
        others = [m for j, m in enumerate(ours.moves) if j != i]
        k = fit_gyro_matrix(others, ours.bias_dps, known_turn_deg=known_turn_deg).scale_matrix
        before, after = ours.stills[i], ours.stills[i + 1]
        station_deg.append(
            move_residual_deg(
                move.t,
                (move.rates_dps - ours.bias_dps) @ np.linalg.inv(k).T,
                move.gravity_before,
                move.gravity_after,
            )
        )
        span = slice(before.stop - 1, after.start + 1)  # the samples of the station's move
        imucal_deg.append(
            move_residual_deg(
                move.t,
                gyr[span],
                acc[before.start : before.stop].mean(axis=0),
                acc[after.start : after.stop].mean(axis=0),
            )
        )
    return np.array(station_deg), np.array(imucal_deg)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("imucal_repo", type=Path, help="a clone of mad-lab-fau/imucal")
    parser.add_argument("--json", action="store_true", help="the figures as JSON")
    parser.add_argument(
        "--known-turn-deg",
        type=float,
        default=None,
        help="declare the session's whole turns (360) to the station's gyro fit",
    )
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        stream_csv = as_station_stream(args.imucal_repo / SESSION, Path(tmp))
        ours = station(stream_csv, args.known_turn_deg)
    theirs = imucal(args.imucal_repo)
    ours_held, imucal_held = held_out(ours["result"], theirs["calibrated"], args.known_turn_deg)
    rows = []
    for i, axis in enumerate("xyz"):
        rows.append(
            {
                "axis": axis,
                "acc_bias_mg": [
                    ours["acc_bias_ms2"][i] / G0 * 1e3,
                    theirs["acc_bias_ms2"][i] / G0 * 1e3,
                ],
                "acc_scale": [ours["acc_scale"][i], theirs["acc_scale"][i]],
                "gyr_bias_dps": [ours["gyr_bias_dps"][i], theirs["gyr_bias_dps"][i]],
                "gyr_scale": [ours["gyr_scale"][i], theirs["gyr_scale"][i]],
            }
        )
    held = {
        "station_rms_deg": float(np.sqrt(np.mean(ours_held**2))),
        "imucal_rms_deg": float(np.sqrt(np.mean(imucal_held**2))),
        "station_deg": ours_held.tolist(),
        "imucal_deg": imucal_held.tolist(),
    }
    if args.json:
        document = {"poses": ours["poses"], "moves": ours["moves"], "axes": rows}
        print(json.dumps(document | {"held_out": held}))
        return
    turns = ", ".join(f"{a:.2f}°" for a in ours["turns_deg"]) or "none declared"
    print(
        f"station: {ours['poses']} still poses and {ours['moves']} moves found by itself; "
        f"known turns as fitted: {turns}"
    )
    print(
        f"held-out moves ({len(ours_held)}, each predicted by the station's K from the others; "
        f"imucal's calibration from its own regions): RMS station "
        f"{held['station_rms_deg']:.3f}°, imucal {held['imucal_rms_deg']:.3f}°; per move "
        f"station {np.round(ours_held, 3).tolist()}, imucal {np.round(imucal_held, 3).tolist()}"
    )
    print(
        "| axis | acc bias: station | imucal | Δ | acc scale: station | imucal | Δ "
        "| gyro bias: station | imucal | Δ | gyro scale: station | imucal | Δ |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        (ab, tb), (asc, tsc) = r["acc_bias_mg"], r["acc_scale"]
        (gb, tgb), (gs, tgs) = r["gyr_bias_dps"], r["gyr_scale"]
        print(
            f"| {r['axis']} | {ab:.2f} mg | {tb:.2f} mg | {ab - tb:+.2f} mg "
            f"| {asc:.5f} | {tsc:.5f} | {(asc / tsc - 1) * 1e6:+.0f} ppm "
            f"| {gb:+.4f} | {tgb:+.4f} | {gb - tgb:+.4f} deg/s "
            f"| {gs:.4f} | {tgs:.4f} | {(gs / tgs - 1) * 1e2:+.2f} % |"
        )


if __name__ == "__main__":
    main()
