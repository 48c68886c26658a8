"""The report's parameters and the limits their capability is measured against.

Each parameter belongs to a limits family (``offset``, ``sensitivity``,
``verification_error``, ``pose_noise``, ``gyro_bias``: the check codes of a limits
profile). :func:`default_bounds` is the one place bounds enter the report: the
datasheet figures of the KXM52-1050 behind the ADS7829 (brief, Table 1).
"""

from dataclasses import dataclass
from typing import Literal

from station.sensor import NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G

#: ``(lower, upper)``; ``None`` for an unbounded side.
Bound = tuple[float | None, float | None]

#: Limits family → bounds.
Bounds = dict[str, Bound]

#: 0 g offset spread over −40…125 °C: ±167 mV = ±207 counts.
OFFSET_SPREAD_COUNTS = 207.0
#: Sensitivity tolerance over −40…125 °C.
SENSITIVITY_TOLERANCE = 0.05


def default_bounds() -> Bounds:
    """The datasheet bounds per limits family (counts, counts/g, mg, counts, deg/s)."""
    return {
        "offset": (
            NOMINAL_OFFSET_COUNTS - OFFSET_SPREAD_COUNTS,
            NOMINAL_OFFSET_COUNTS + OFFSET_SPREAD_COUNTS,
        ),
        "sensitivity": (
            NOMINAL_SENSITIVITY_COUNTS_PER_G * (1 - SENSITIVITY_TOLERANCE),
            NOMINAL_SENSITIVITY_COUNTS_PER_G * (1 + SENSITIVITY_TOLERANCE),
        ),
        "verification_error": (None, 30.0),
        "pose_noise": (None, 8.0),
        "gyro_bias": (-10.0, 10.0),
    }


@dataclass(frozen=True)
class ParameterSpec:
    """One reported parameter: its name, limits family, unit and where it is stored.

    ``source`` is ``runs`` (one value per run) or ``poses`` (one value per pose);
    ``column`` is the column, or for ``gyro_bias`` the axis inside the run's gyro
    document.
    """

    name: str
    family: str
    unit: str
    source: Literal["runs", "poses"]
    column: str


PARAMETERS: tuple[ParameterSpec, ...] = (
    *(ParameterSpec(f"offset_{a}", "offset", "counts", "runs", f"offset_{a}") for a in "xyz"),
    *(
        ParameterSpec(f"sensitivity_{a}", "sensitivity", "counts/g", "runs", f"sensitivity_{a}")
        for a in "xyz"
    ),
    ParameterSpec(
        "verification_error", "verification_error", "mg", "runs", "verification_error_mg"
    ),
    *(ParameterSpec(f"pose_noise_{a}", "pose_noise", "counts", "poses", f"std_{a}") for a in "xyz"),
    *(ParameterSpec(f"gyro_bias_{a}", "gyro_bias", "deg/s", "runs", a) for a in "xyz"),
)

#: The calibration coefficients, each with an individuals (I-MR) control chart.
COEFFICIENTS: tuple[str, ...] = tuple(
    f"{kind}_{a}" for kind in ("offset", "sensitivity") for a in "xyz"
)
