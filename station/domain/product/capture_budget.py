"""How long a pose's window must be: the accuracy budget the limits profile implies.

Model. Each accelerometer axis of a still window is the pose's true reading plus white
noise of standard deviation σ (ADC counts), so the window's mean over ``n`` samples has
the standard error ``σ/√n``. The calibration turns the pose means' errors into offset and
sensitivity errors; for the station's six poses spread evenly over the sphere, the
Cramér–Rao bound (unknown gravity directions as nuisance parameters), which the paper's
eq. 10 attains ([Song2006]_; ``docs/benchmarks.md``, *calibration*: √CRB 0.0897
counts of offset and 0.1653 counts/g of sensitivity at σ = 0.1 counts per pose mean), is

    σ_offset = 0.897 · σ_mean        σ_sensitivity = 1.653 · σ_mean

and more poses only lower both. The budget asks that the noise's share of every offset
and sensitivity be at most ``fraction`` of the width of its limits
(``offset_counts``, ``sensitivity_counts_per_g``):

    σ_mean ≤ b = fraction · min(offset width / 0.897, sensitivity width / 1.653)

With the shipped profile (widths 414 counts and 81.92 counts/g) and the default
fraction 1/400 the sensitivity binds: b = 0.124 counts, so a unit with 1 count of noise
needs 65 samples (the floor takes over), one with 2 counts 260, one with 4 counts 1041.

:class:`WindowPolicy` is the rule a still window ends by: at the ceiling, or once it
holds at least the floor and every axis' standard error (the window's sample standard
deviation over √n) is within the budget. A fixed window is the policy whose floor and
ceiling are both the window's length.
"""

import math
from dataclasses import dataclass
from typing import Final, Self

from pydantic import BaseModel, ConfigDict, Field, model_validator

from station.domain.arrays import FloatArray
from station.domain.product.limits import Bounds, LimitsProfile

#: √CRB per unit of pose-mean standard error, six poses spread over the sphere
#: (``docs/benchmarks.md``, calibration: 0.0897 and 0.1653 at σ = 0.1 counts).
CRB_OFFSET_PER_SIGMA: Final = 0.897
CRB_SENSITIVITY_PER_SIGMA: Final = 1.653


class AdaptiveCapture(BaseModel):
    """Floor, ceiling and accuracy budget of adaptive windows (``[run.adaptive]``)."""

    model_config = ConfigDict(frozen=True, extra="forbid")

    floor_samples: int = Field(
        256,
        ge=64,
        description="shortest window: half a second at 500/s, long enough for the "
        "stillness checks (a quarter of 64 samples for the drift check)",
    )
    ceiling_samples: int = Field(
        4096,
        ge=64,
        description="longest window: 8.2 s at 500/s, four fixed windows; a unit this "
        "noisy is captured at the ceiling and judged by its pose noise limit",
    )
    budget_fraction: float = Field(
        0.0025,
        gt=0,
        le=0.1,
        description="noise's standard uncertainty of each offset and sensitivity, as a "
        "share of its limits' width (1/400: ±3σ spans 1.5 % of the tolerance)",
    )

    @model_validator(mode="after")
    def _ordered(self) -> Self:
        if self.floor_samples > self.ceiling_samples:
            raise ValueError(
                f"floor_samples {self.floor_samples} is above ceiling_samples "
                f"{self.ceiling_samples}"
            )
        return self


def _width(bounds: Bounds) -> float:
    """The bounds' width (infinite when a side is open)."""
    low, high = bounds.sides
    return high - low


def pose_budget_counts(profile: LimitsProfile, fraction: float) -> float:
    """Largest standard error of a pose mean (counts) the profile's limits allow.

    Infinite when neither the offset nor the sensitivity limits are two-sided: nothing
    then asks for more than the floor.
    """
    return fraction * min(
        _width(profile.offset_counts) / CRB_OFFSET_PER_SIGMA,
        _width(profile.sensitivity_counts_per_g) / CRB_SENSITIVITY_PER_SIGMA,
    )


def standard_error(accel_std: FloatArray, count: int) -> float:
    """The largest per-axis standard error of a window's mean (counts)."""
    return float(accel_std.max()) / math.sqrt(count)


@dataclass(frozen=True)
class WindowPolicy:
    """When a still window is long enough: floor ≤ n ≤ ceiling, standard error ≤ budget."""

    floor: int
    ceiling: int
    budget_counts: float = math.inf

    @classmethod
    def fixed(cls, samples: int) -> Self:
        """Every window exactly ``samples`` long (the station's default)."""
        return cls(samples, samples)

    @classmethod
    def adaptive(cls, settings: AdaptiveCapture, profile: LimitsProfile) -> Self:
        """Windows between the settings' floor and ceiling, to the profile's budget."""
        return cls(
            settings.floor_samples,
            settings.ceiling_samples,
            pose_budget_counts(profile, settings.budget_fraction),
        )

    def enough(self, accel_std: FloatArray, count: int) -> bool:
        """Whether a still window of ``count`` samples with these spreads may end."""
        if count >= self.ceiling:
            return True
        return count >= self.floor and standard_error(accel_std, count) <= self.budget_counts

    def samples_needed(self, accel_std: FloatArray) -> int:
        """The window length the spreads ``accel_std`` call for, floor to ceiling."""
        if not math.isfinite(self.budget_counts) or self.floor == self.ceiling:
            return self.floor
        need = math.ceil((float(accel_std.max()) / self.budget_counts) ** 2)
        return min(self.ceiling, max(self.floor, need))
