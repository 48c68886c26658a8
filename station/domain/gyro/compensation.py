"""Compensation: the applied rate from gyro and accelerometer samples, inverting the model.

The model of :mod:`station.domain.gyro.model` is, for one sample with specific force a,
linear in the rate ω::

    gyro − b − B·a = (S + diag(N·a))·ω

so each sample's rate is the solution of a 3-by-3 system ([Park2014]_ eq. 4 solved
for ω, exact rather than to first order). All samples are solved at once by a batched
``numpy.linalg.solve``.
"""

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.gyro.model import GyroErrorModel


def compensate(model: GyroErrorModel, gyro: FloatArray, acc: FloatArray) -> FloatArray:
    """Rate (N-by-3, deg/s) from gyro output (N-by-3, deg/s) and specific force (N-by-3, g)."""
    gyro = np.asarray(gyro, dtype=np.float64)
    acc = np.asarray(acc, dtype=np.float64)
    if gyro.ndim != 2 or gyro.shape[1] != 3 or acc.shape != gyro.shape:
        raise ValueError(
            f"gyro and acc must both be N-by-3 arrays, not {gyro.shape} and {acc.shape}"
        )
    matrices = np.broadcast_to(model.scale, (gyro.shape[0], 3, 3)).copy()
    diagonal = np.arange(3)
    matrices[:, diagonal, diagonal] += acc @ model.n_g.T
    rhs = gyro - model.bias - acc @ model.bias_g.T
    return np.asarray(np.linalg.solve(matrices, rhs[:, :, None])[:, :, 0], dtype=np.float64)
