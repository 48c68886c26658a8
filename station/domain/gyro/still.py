"""The gyros in the station's still poses: bias, noise, and bias against gravity.

In a still pose the rate is zero, so each gyro's mean is its bias. Over poses with
different gravity directions, a bias-form g-sensitivity would show as a slope::

    m_pk = b_k + Σ_j K_kj·g_pj        p = 1…P poses, k gyro axis, g in g

fitted by least squares (:mod:`station.domain.gyro.lsq`). [Park2014]_ (section 2.2) says a
tuning-fork gyro's g-sensitivity is a scale-factor error, so K should be zero: the
extra-sum-of-squares F-test of K_k· = 0 (3 and P − 4 degrees of freedom, residual
variance from the poses themselves) says whether the slope is consistent with zero
at level α. Bias is the mean over the poses, checked against a limit when one is
given; noise the RMS of the per-pose noise.
"""

from typing import Annotated, Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from station.domain.arrays import FloatArray
from station.domain.errors import InputError
from station.domain.gyro.lsq import solve
from station.domain.sensors.record_bounds import (
    MEASURE_MAX,
    GyroRate,
    GyroSpread,
    Measure,
    Probability,
    Text,
)
from station.domain.sensors.sensor import AXES, Axis

MIN_POSES_FOR_SLOPE = 4
MIN_POSES_FOR_TEST = 5


#: One value per gravity axis (x, y, z).
Slope3 = Annotated[list[Measure], Field(min_length=3, max_length=3)]


class GyroAxisStill(BaseModel):
    """One gyro's figures over the still poses (bounds:
    :mod:`station.domain.sensors.record_bounds`)."""

    model_config = ConfigDict(allow_inf_nan=False)

    axis: Axis
    bias_dps: GyroRate
    noise_dps: GyroSpread
    slope_dps_per_g: Slope3 | None
    slope_stderr_dps_per_g: Slope3 | None
    slope_p_value: Probability | None
    slope_consistent_with_zero: bool | None
    bias_within_limit: bool | None
    reason: Text | None = None


class GyroStillSummary(BaseModel):
    """The three gyros over the still poses of one run."""

    model_config = ConfigDict(allow_inf_nan=False)

    poses: Annotated[int, Field(ge=0, le=64)]
    alpha: Annotated[float, Field(gt=0, lt=1)]
    bias_limit_dps: Annotated[float, Field(gt=0, le=MEASURE_MAX)] | None
    axes: Annotated[list[GyroAxisStill], Field(max_length=3)]

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dictionary, for storage and the API."""
        return self.model_dump(mode="json")

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "GyroStillSummary":
        """Read back a :meth:`to_dict` answer (validated)."""
        return cls.model_validate(data)


def _checked(name: str, value: FloatArray, poses: int | None) -> FloatArray:
    array = np.asarray(value, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 3 or (poses is not None and array.shape[0] != poses):
        expected = "N-by-3" if poses is None else f"{poses}-by-3"
        raise InputError(f"{name}: expected an {expected} array, got shape {array.shape}")
    bad = np.flatnonzero(~np.all(np.isfinite(array), axis=1))
    if bad.size:
        raise InputError(f"{name}: pose {int(bad[0])}: value is not finite")
    return array


def summarize_still_poses(
    gyro_means: FloatArray,
    pose_noise: FloatArray,
    gravity: FloatArray,
    alpha: float = 0.01,
    bias_limit_dps: float | None = None,
) -> GyroStillSummary:
    """Bias, noise and bias-vs-gravity slope of each gyro (module docstring).

    ``gyro_means`` P-by-3 deg/s, ``pose_noise`` P-by-3 deg/s (standard deviation in each
    pose), ``gravity`` P-by-3 g (from the calibrated accelerometer); pose ``p`` is row p.
    With ``bias_limit_dps`` each gyro's |bias| is checked against it.
    """
    # Imported here: scipy.special takes ~0.5 s to load, and the results server, which
    # imports this module with the run record, rarely needs it (the server's start-up).
    from scipy import special

    if bias_limit_dps is not None and not bias_limit_dps > 0:
        raise InputError(f"bias limit: must be positive, got {bias_limit_dps:g} deg/s")
    means = _checked("gyro means", gyro_means, None)
    poses = means.shape[0]
    if poses == 0:
        raise InputError("gyro means: no poses")
    noise = _checked("pose noise", pose_noise, poses)
    if np.any(noise < 0):
        raise InputError(f"pose noise: pose {int(np.argmax(np.any(noise < 0, axis=1)))}: negative")
    g = _checked("gravity", gravity, poses)
    design = np.column_stack([np.ones(poses), g])
    axes = []
    for k in range(3):
        y = means[:, k]
        bias = float(np.mean(y))
        rms_noise = float(np.sqrt(np.mean(noise[:, k] ** 2)))
        ls = solve(design, y) if poses >= MIN_POSES_FOR_SLOPE else None
        slope = stderr = p_value = consistent = reason = None
        if ls is None or ls.rank < 4:
            reason = (
                f"the slope needs at least {MIN_POSES_FOR_SLOPE} poses"
                if ls is None
                else "the poses' gravity vectors do not span three dimensions"
            )
        else:
            slope = [float(v) for v in ls.coef[1:]]
            if poses < MIN_POSES_FOR_TEST:
                reason = f"the test of the slope needs at least {MIN_POSES_FOR_TEST} poses"
            else:
                stderr = [float(v) for v in ls.stderr[1:]]
                rss0 = float(np.sum((y - bias) ** 2))
                f = ((rss0 - ls.rss) / 3) / (max(ls.rss, 1e-300) / ls.dof)
                p_value = float(special.fdtrc(3, ls.dof, min(max(f, 0.0), 1e300)))
                consistent = p_value >= alpha
        axes.append(
            GyroAxisStill(
                axis=AXES[k],
                bias_dps=bias,
                noise_dps=rms_noise,
                slope_dps_per_g=slope,
                slope_stderr_dps_per_g=stderr,
                slope_p_value=p_value,
                slope_consistent_with_zero=consistent,
                bias_within_limit=None if bias_limit_dps is None else abs(bias) <= bias_limit_dps,
                reason=reason,
            )
        )
    return GyroStillSummary(poses=poses, alpha=alpha, bias_limit_dps=bias_limit_dps, axes=axes)
