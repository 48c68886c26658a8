"""The units an accelerometer's readings were declared in, and its results stated in them.

The solve works in ADC counts of the putter's sensor (zero 2048, 819.2 counts/g,
[Song2006]_ Table 1): readings declared in ``g`` or ``m/s2`` are mapped to those counts
first, ``a → zero + a/u·counts_per_g`` with u = 1 (g) or g₀ = 9.80665 m/s² (the standard
gravity that defines the unit g), and the results are mapped back, so another IMU's user
reads them in the units the recording declared. Per axis the model is

    reading = s·(true acceleration) + o

- ``counts``: o in counts, s in counts/g, as solved;
- ``g``: o in g, s a dimensionless scale factor (1 for a perfect axis);
- ``m/s2``: o in m/s², s the same dimensionless scale factor.

An offset's change of unit is affine (the zero moves), a sensitivity's, a standard
error's, an expanded uncertainty's and a residual's only a scale. The matrix ``C`` that
maps ``raw − o`` to g becomes dimensionless for ``g`` and ``m/s2`` (it maps a reading
less its offset to the same unit).
"""

from dataclasses import dataclass
from typing import Final, Literal

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.calibration.model import xyz
from station.domain.sensors.sensor import NOMINAL_OFFSET_COUNTS, NOMINAL_SENSITIVITY_COUNTS_PER_G

AccelUnits = Literal["counts", "g", "m/s2"]

#: Standard gravity, m/s² (the definition of 1 g).
STANDARD_GRAVITY: Final = 9.80665
#: What a sensitivity is stated in, by declared accelerometer unit.
SENSITIVITY_UNITS: Final[dict[AccelUnits, str]] = {
    "counts": "counts/g",
    "g": "1 (scale factor)",
    "m/s2": "1 (scale factor)",
}


@dataclass(frozen=True)
class DeclaredUnits:
    """An accelerometer's declared unit and the counts its readings are solved in."""

    accel: AccelUnits = "counts"
    zero_counts: float = NOMINAL_OFFSET_COUNTS
    counts_per_g: float = NOMINAL_SENSITIVITY_COUNTS_PER_G

    @property
    def per_g(self) -> float:
        """One g in the declared unit (1 count per count for ``counts``: no change)."""
        return {"counts": 1.0, "g": 1.0, "m/s2": STANDARD_GRAVITY}[self.accel]

    @property
    def _counts_per_unit(self) -> float:
        """Counts of the solve per declared unit of acceleration."""
        return 1.0 if self.accel == "counts" else self.counts_per_g / self.per_g

    def to_counts(self, readings: FloatArray) -> FloatArray:
        """Readings in the declared unit as counts of the solve."""
        if self.accel == "counts":
            return readings
        return self.zero_counts + readings * self._counts_per_unit

    def spread_to_counts(self, spread: FloatArray) -> FloatArray:
        """A spread of readings in the declared unit as counts of the solve."""
        return spread * self._counts_per_unit

    def offset(self, counts: FloatArray) -> FloatArray:
        """An offset in counts of the solve, in the declared unit."""
        if self.accel == "counts":
            return counts
        return (counts - self.zero_counts) / self._counts_per_unit

    def spread(self, counts: FloatArray) -> FloatArray:
        """A difference of readings (a spread, a standard error, a U) in the declared unit."""
        return counts / self._counts_per_unit

    def residual(self, counts: float) -> float:
        """A residual (or its limit) in counts of the solve, in the declared unit."""
        return counts / self._counts_per_unit

    def sensitivity(self, counts_per_g: FloatArray) -> FloatArray:
        """A sensitivity (or its standard error, or its U) in counts/g, as declared:
        counts/g for counts, else the dimensionless scale factor."""
        return counts_per_g if self.accel == "counts" else counts_per_g / self.counts_per_g

    def matrix(self, counts_to_g: FloatArray) -> FloatArray:
        """``C`` (counts → g) as the map from a reading less its offset to the same unit."""
        return counts_to_g if self.accel == "counts" else counts_to_g * self.counts_per_g

    def names(self) -> dict[str, str]:
        """The JSON's ``units``: what offset, sensitivity and residual limits are in."""
        unit = self.accel
        return {"offset": unit, "sensitivity": SENSITIVITY_UNITS[unit], "residual": unit}

    def restate(self, payload: dict[str, object]) -> dict[str, object]:
        """A solve's JSON (``Solution.to_dict`` with ``uncertainty``) in the declared unit,
        with ``units`` naming it. Counts come out unchanged but for ``units``."""
        out = dict(payload)
        out["units"] = self.names()
        if self.accel == "counts":
            return out
        out["offset"] = xyz(self.offset(_array(out["offset"])))
        out["sensitivity"] = xyz(self.sensitivity(_array(out["sensitivity"])))
        out["matrix"] = self.matrix(np.asarray(out["matrix"], dtype=np.float64)).tolist()
        se = out.get("standard_errors")
        if isinstance(se, dict):
            out["standard_errors"] = se | {
                "offset": xyz(self.spread(_array(se["offset"]))),
                "sensitivity": xyz(self.sensitivity(_array(se["sensitivity"]))),
            }
        u = out.get("uncertainty")
        if isinstance(u, dict):
            restated = dict(u)
            if "offset" in u:
                restated["offset"] = xyz(self.spread(_array(u["offset"])))
            if "sensitivity" in u:
                restated["sensitivity"] = xyz(self.sensitivity(_array(u["sensitivity"])))
            if "matrix" in u:  # the nine-parameter matrix's U scales as the matrix
                restated["matrix"] = self.matrix(np.asarray(u["matrix"], dtype=np.float64)).tolist()
            out["uncertainty"] = restated
        for counts_key, key in (
            ("residual_limit_counts", "residual_limit"),
            ("studentised_max_counts", "studentised_max"),
        ):
            value = out.pop(counts_key, None)
            out[key] = None if not isinstance(value, float) else self.residual(value)
        return out


def _array(values: object) -> FloatArray:
    """``{"x", "y", "z"}`` as an array."""
    if not isinstance(values, dict):
        raise TypeError(f"expected {{x, y, z}}, got {values!r}")
    return np.array([values[a] for a in "xyz"], dtype=np.float64)
