"""A second simulator of the line's units, written from the datasheets alone.

It knows the two products as their datasheets state them and nothing of the station's
own simulator (``station.device``): a unit is its true zero-g offset and sensitivity per
axis, held exactly along ±x, ±y and ±z, so each still pose's mean is the sensor model
``a = offset + sensitivity · g`` (counts) with ``g`` one unit vector. The truth is then
known in closed form: per axis, ``offset = (p⁺ + p⁻)/2`` and
``sensitivity = (p⁺ − p⁻)/2`` [Song2006, eqs. 2 and 3], which is what a run reports as
its coefficients and what the results server's own solve must reproduce.

:class:`CoupledUnit` is a unit as the datasheet bounds it rather than its nominal: its
offsets, sensitivities and cross-axis coupling drawn within the datasheet's spreads, its
poses held by a fixture a few degrees off the axes, each pose the mean of the ADC's rounded
noisy samples, written as the pose file ``calstation solve`` reads. Its truth is known,
so the coverage of the station's U can be counted on it.

:func:`run_payload` writes the body ``POST /api/v1/runs`` takes (``docs/api.md``, "The
run record"), as plain JSON built here. The limits profile a run carries is the
station's configuration (``station/domain/profiles/limits.toml``), looked up by the
product's profile name: a run must carry the document the station sends.
"""

import uuid
from dataclasses import dataclass
from datetime import datetime, timedelta
from pathlib import Path
from typing import Any

import numpy as np

from station.domain.product.limits import load_profiles

AXES = "xyz"


@dataclass(frozen=True)
class Datasheet:
    """One product's accelerometer as its datasheet gives it (``docs/protocol.md``,
    ``docs/station.md``): an ``adc_bits`` ADC, zero g at ``zero_g_counts``,
    ``counts_per_g``; the limits profile its runs are judged by; a still pose's typical
    sample spread (counts)."""

    part_number: str
    adc_bits: int
    zero_g_counts: float
    counts_per_g: float
    limits_profile: str
    pose_std_counts: float
    offset_spread_counts: float = 0.0
    sensitivity_spread: float = 0.0
    cross_axis: float = 0.0

    @property
    def adc_max(self) -> int:
        """The largest count the ADC gives: ``2**bits − 1``."""
        return int(2**self.adc_bits) - 1


#: DIXX-A12: KXM52-1050 behind the 12-bit ADS7829: 0…4095, zero g 2048, 819.2 counts/g
#: (660 mV/g of a 3.3 V span over 4096 counts); its 0 g offset within ±167 mV over
#: −40…125 °C (±207 counts), its sensitivity within ±3 % (max. over −40…85 °C), its
#: cross-axis sensitivity 2 % (typical) ([Song2006] Table 1).
A12 = Datasheet("DIXX-A12", 12, 2048.0, 819.2, "kxm52-production", 1.2, 207.0, 0.03, 0.02)
#: DIXX-D16: 16-bit digital accelerometer, ±4 g, offset binary: 0…65535, zero g 32768,
#: 8192 counts/g; offset within ±60 mg (±492 counts), sensitivity within ±3 %.
D16 = Datasheet("DIXX-D16", 16, 32768.0, 8192.0, "dixx-d16-production", 10.0, 492.0, 0.03)
PRODUCTS = (A12, D16)

#: The six exact poses, gravity along +x, −x, +y, −y, +z, −z, with their names.
POSES = (
    ("x_up", 0, 1.0),
    ("x_down", 0, -1.0),
    ("y_up", 1, 1.0),
    ("y_down", 1, -1.0),
    ("z_up", 2, 1.0),
    ("z_down", 2, -1.0),
)


@dataclass(frozen=True)
class Unit:
    """One unit's true accelerometer: offset (counts) and sensitivity (counts/g) per axis."""

    serial: str
    product: Datasheet
    offset: tuple[float, float, float]
    sensitivity: tuple[float, float, float]

    def pose_means(self) -> list[tuple[float, float, float]]:
        """The mean counts of the six poses of :data:`POSES`: ``offset + sensitivity·g``,
        each within the ADC's ``0…adc_max`` (a unit beyond would read its rail)."""
        means = []
        for _, axis, sign in POSES:
            means.append(
                tuple(
                    self.offset[a] + (sign * self.sensitivity[a] if a == axis else 0.0)
                    for a in range(3)
                )
            )
        if not all(0 <= c <= self.product.adc_max for mean in means for c in mean):
            raise ValueError(f"{self.serial}: a pose beyond the ADC of {self.product.part_number}")
        return means  # type: ignore[return-value]

    def coefficients(self) -> tuple[list[float], list[float]]:
        """Offset and sensitivity per axis from the poses alone, the classic six-position
        formulas: ``(p⁺ + p⁻)/2`` and ``(p⁺ − p⁻)/2`` of the axis' own reading."""
        means = self.pose_means()
        offset, sensitivity = [], []
        for axis in range(3):
            up, down = means[2 * axis][axis], means[2 * axis + 1][axis]
            offset.append((up + down) / 2)
            sensitivity.append((up - down) / 2)
        return offset, sensitivity


#: Samples averaged per still pose ([Song2006]: 1024).
SAMPLES_PER_POSE = 1024
#: The six-pose plan: gravity along ±x, ±y, ±z, as a fixture holds them (a few degrees off).
AXIS_DIRECTIONS = np.array([[sign * (a == axis) for a in range(3)] for _, axis, sign in POSES])
#: Twelve poses for the nine-parameter model: the six axes and one diagonal of each face
#: pair in each of the three planes (the cross-axis terms need poses between the axes).
TWELVE_DIRECTIONS = np.vstack(
    [
        AXIS_DIRECTIONS,
        np.array([[1, 1, 0], [-1, 1, 0], [0, 1, 1], [0, -1, 1], [1, 0, 1], [1, 0, -1]], dtype=float)
        / np.sqrt(2.0),
    ]
)


@dataclass(frozen=True)
class CoupledUnit:
    """A unit as its datasheet bounds it, with the cross-axis coupling the six-pose model
    leaves out: a still sample reads ``a = o + diag(s)·(I + M)·g + n``, rounded to the
    ADC's counts, ``g`` the unit gravity vector in the sensor's frame, ``M`` the coupling
    (zero diagonal, each other element within ±``cross_axis``), ``n`` white noise of the
    datasheet's pose spread. Offsets, sensitivities and couplings are drawn uniformly
    within the datasheet's bounds (its nominal ± spread)."""

    product: Datasheet
    offset: np.ndarray
    sensitivity: np.ndarray
    coupling: np.ndarray

    @classmethod
    def draw(cls, rng: np.random.Generator, product: Datasheet) -> "CoupledUnit":
        """One unit drawn within ``product``'s datasheet bounds."""
        offset = product.zero_g_counts + rng.uniform(-1, 1, 3) * product.offset_spread_counts
        scale = 1.0 + rng.uniform(-1, 1, 3) * product.sensitivity_spread
        coupling = rng.uniform(-1, 1, (3, 3)) * product.cross_axis
        np.fill_diagonal(coupling, 0.0)
        return cls(product, offset, product.counts_per_g * scale, coupling)

    @property
    def response(self) -> np.ndarray:
        """Counts per g of gravity along each sensor axis: ``diag(s)·(I + M)``."""
        return np.diag(self.sensitivity) @ (np.eye(3) + self.coupling)

    def true_sensitivity(self, model: str) -> np.ndarray:
        """The sensitivities as ``model`` reports them (``docs/calibration.md``): six, each
        axis' own counts per g, ``s``; nine, ``1/diag(C)`` of the upper-triangular C with
        ``C·(a − o)`` of unit length (x the reference axis, y in the x-y plane): C is the
        triangular factor R of ``response⁻¹ = Q·R`` (a rotation Q leaves lengths alone)."""
        if model == "six":
            return self.sensitivity
        r = np.linalg.qr(np.linalg.inv(self.response))[1]
        return np.asarray(1.0 / np.abs(np.diag(r)))

    def pose_file(
        self, rng: np.random.Generator, directions: np.ndarray, tilt_deg: float, path: Path
    ) -> Path:
        """A pose file (``ax,ay,az,sx,sy,sz,n``, ``calstation solve``'s) of the unit held
        along ``directions``, each turned by up to ``tilt_deg`` about a random axis: each
        pose the mean and sample spread of :data:`SAMPLES_PER_POSE` rounded samples."""
        rows = ["ax,ay,az,sx,sy,sz,n"]
        for u in directions:
            axis = np.cross(u, rng.standard_normal(3))
            axis /= np.linalg.norm(axis)
            angle = np.radians(rng.uniform(0.0, tilt_deg))
            g = (
                u * np.cos(angle)
                + np.cross(axis, u) * np.sin(angle)
                + axis * np.dot(axis, u) * (1 - np.cos(angle))
            )
            clean = self.offset + self.response @ g
            noise = rng.normal(0.0, self.product.pose_std_counts, (SAMPLES_PER_POSE, 3))
            samples = np.clip(np.round(clean + noise), 0, self.product.adc_max)
            mean, spread = samples.mean(axis=0), samples.std(axis=0, ddof=1)
            rows.append(",".join(f"{v:.6f}" for v in (*mean, *spread)) + f",{SAMPLES_PER_POSE}")
        path.write_text("\n".join(rows) + "\n", encoding="utf-8")
        return path


def limits_ref(product: Datasheet) -> dict[str, Any]:
    """The limits reference and profile document a station of ``product`` sends."""
    document: dict[str, Any] = load_profiles()[product.limits_profile].ref.model_dump(mode="json")
    return document


def bounds(product: Datasheet, quantity: str) -> tuple[float | None, float | None]:
    """The product's limits of ``quantity`` (``offset_counts``, ``sensitivity_counts_per_g``),
    read from the profile document its runs carry: ``(lower, upper)``, ``None`` for an
    open side."""
    bound = limits_ref(product)["profile"].get(quantity) or {}
    return bound.get("lower"), bound.get("upper")


def _xyz(values: list[float] | tuple[float, ...]) -> dict[str, float]:
    return dict(zip(AXES, values, strict=True))


def run_payload(
    unit: Unit,
    *,
    station_id: str,
    started_at: datetime,
    aborted: bool = False,
    passed_before: bool = False,
    attempts_before: int = 0,
    seconds: float = 90.0,
) -> dict[str, Any]:
    """The body of ``POST /api/v1/runs`` for one run of ``unit``.

    A completed run reports the six poses and the coefficients they give; its verdict is
    the limits' (``docs/station.md``, "Verdict"): every offset and sensitivity within its
    product's bounds, else one failure per value outside (code ``offset`` or
    ``sensitivity``, with the axis, value and bounds). An ``aborted`` run is the operator's
    abort before the write-back: a failure ``aborted``, no coefficients. The disposition
    is ``ship`` for a pass, ``retest`` for a failure (``rework`` once three attempts of
    the unit failed, the default retest limit); an abort's is ``ship`` when the unit had
    passed before (it still holds its verified coefficients), else ``retest``.
    """
    product = unit.product
    run: dict[str, Any] = {
        "run_id": str(uuid.uuid4()),
        "serial": unit.serial,
        "station_id": station_id,
        "operator_id": "op-model",
        "part_number": product.part_number,
        "fixture_slot": 1,
        "started_at": started_at.isoformat(),
        "finished_at": (started_at + timedelta(seconds=seconds)).isoformat(),
        "software_version": "model-1",
        "algorithm": "autocal-ls",
        "model": "six",
        "limits": limits_ref(product),
        "poses": [
            {
                "index": index,
                "name": name,
                "role": "fit",
                "mean": _xyz(mean),
                "std": _xyz([product.pose_std_counts] * 3),
                "sample_count": 1024,
            }
            for index, ((name, _, _), mean) in enumerate(zip(POSES, unit.pose_means(), strict=True))
        ],
    }
    if aborted:
        failure = {"code": "aborted", "message": "aborted by the operator"}
        disposition = "ship" if passed_before else "retest"
        return {**run, "verdict": "fail", "disposition": disposition, "failures": [failure]}
    offset, sensitivity = unit.coefficients()
    failures = [
        _out_of_limits(product, code, quantity, axis, value)
        for code, quantity, values in (
            ("offset", "offset_counts", offset),
            ("sensitivity", "sensitivity_counts_per_g", sensitivity),
        )
        for axis, value in zip(AXES, values, strict=True)
        if not _within(value, bounds(product, quantity))
    ]
    verdict = "fail" if failures else "pass"
    disposition = "ship" if not failures else "rework" if attempts_before >= 2 else "retest"
    return {
        **run,
        "verdict": verdict,
        "disposition": disposition,
        "failures": failures,
        "coefficients": {
            "offset": _xyz(offset),
            "sensitivity": _xyz(sensitivity),
            "matrix": [
                [1.0 / s if i == j else 0.0 for j in range(3)] for i, s in enumerate(sensitivity)
            ],
        },
    }


def _within(value: float, limits: tuple[float | None, float | None]) -> bool:
    lower, upper = limits
    return (lower is None or value >= lower) and (upper is None or value <= upper)


def _out_of_limits(
    product: Datasheet, code: str, quantity: str, axis: str, value: float
) -> dict[str, Any]:
    lower, upper = bounds(product, quantity)
    return {
        "code": code,
        "message": f"{code} {axis} {value:.6g} outside {lower}…{upper}",
        "measured": value,
        "lower": lower,
        "upper": upper,
        "axis": axis,
    }
