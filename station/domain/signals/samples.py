"""A block of the putter's samples with named columns, and the summary of a window.

The driver hands samples out as N-by-8 float64 rows (:data:`SAMPLE_COLUMNS`): the
unwrapped sequence number, accelerometer x, y, z (ADC counts, or g from the
calibrated stream), gyro x, y, z in deg/s and temperature in °C. :class:`SampleBlock`
names those columns (views, no copies) so that no caller spells ``rows[:, 1:4]``;
:meth:`SampleBlock.summary` is the one place a still window's means and spreads
are computed.
"""

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final, Self

import numpy as np
import numpy.typing as npt

from station.domain.arrays import FloatArray

#: Columns of a block of samples (N-by-8 float64), in order.
SAMPLE_COLUMNS: Final = ("seq", "ax", "ay", "az", "gx", "gy", "gz", "temp")
_SEQ: Final = 0
_ACCEL: Final = slice(1, 4)
_GYRO: Final = slice(4, 7)
_TEMPERATURE: Final = 7


@dataclass(frozen=True, slots=True)
class WindowSummary:
    """Means and sample standard deviations (``ddof=1``) of a window, per column.

    Accelerometer in ADC counts (g for calibrated samples), gyros in deg/s,
    temperature in °C. The spreads are sample standard deviations: the window is a
    sample of the unit's noise, and the stored pose spread, the stillness limits and
    the spread limits of the profile all read it so. Over the 1,024 samples of a pose
    they differ from the population form by 0.05 %.
    """

    count: int
    accel_mean: FloatArray
    accel_std: FloatArray
    gyro_mean: FloatArray
    gyro_std: FloatArray
    temperature_c: float
    temperature_std_c: float


@dataclass(frozen=True, slots=True)
class SampleBlock:
    """N samples as rows of :data:`SAMPLE_COLUMNS`; the columns by name."""

    rows: FloatArray

    def __post_init__(self) -> None:
        if self.rows.ndim != 2 or self.rows.shape[1] != len(SAMPLE_COLUMNS):
            raise ValueError(
                f"a sample block has {len(SAMPLE_COLUMNS)} columns, got shape {self.rows.shape}"
            )

    @classmethod
    def empty(cls) -> Self:
        """No samples."""
        return cls(np.empty((0, len(SAMPLE_COLUMNS))))

    @classmethod
    def from_columns(
        cls, seq: FloatArray, accel: FloatArray, gyro: FloatArray, temperature: FloatArray
    ) -> Self:
        """Assemble a block from its columns (``accel`` and ``gyro`` N-by-3)."""
        return cls(np.column_stack((seq, accel, gyro, temperature)).astype(np.float64))

    @classmethod
    def concat(cls, blocks: Sequence["SampleBlock"]) -> Self:
        """The samples of ``blocks``, in order, as one block (no copy for a single one)."""
        if len(blocks) == 1:
            return cls(blocks[0].rows)
        if not blocks:
            return cls.empty()
        return cls(np.concatenate([block.rows for block in blocks]))

    def __len__(self) -> int:
        return len(self.rows)

    def __getitem__(self, which: slice | npt.NDArray[np.bool_] | np.bool_) -> Self:
        """The samples a slice or a mask selects, as a block (rows, never columns)."""
        return type(self)(self.rows[which])

    @property
    def seq(self) -> FloatArray:
        """Sequence numbers (a view: writing to it changes the block)."""
        return self.rows[:, _SEQ]

    @property
    def accel(self) -> FloatArray:
        """Accelerometer x, y, z, N-by-3."""
        return self.rows[:, _ACCEL]

    @property
    def gyro(self) -> FloatArray:
        """Gyro rates x, y, z in deg/s, N-by-3."""
        return self.rows[:, _GYRO]

    @property
    def temperature(self) -> FloatArray:
        """Temperature in °C."""
        return self.rows[:, _TEMPERATURE]

    @property
    def span(self) -> float:
        """Samples from the first to the last sequence number, both included."""
        return float(self.rows[-1, _SEQ] - self.rows[0, _SEQ] + 1)

    def summary(self) -> WindowSummary:
        """Means and sample standard deviations of every column.

        A single sample shows no spread: its standard deviations are 0 (the live view
        judges the first sample of a stream too). An empty block has no summary.
        """
        if not len(self.rows):
            raise ValueError("an empty block of samples has no summary")
        # What ndarray.mean and .std(ddof=1) compute, to the bit, without their wrappers'
        # overhead (the live view summarises a window at every pass of the loop, per slot).
        rows = self.rows
        count = len(rows)
        mean = rows.sum(axis=0) / count
        if count > 1:
            deviation = rows - mean
            std = np.sqrt((deviation * deviation).sum(axis=0) / (count - 1))
        else:
            std = np.zeros_like(mean)
        return WindowSummary(
            count=count,
            accel_mean=mean[_ACCEL],
            accel_std=std[_ACCEL],
            gyro_mean=mean[_GYRO],
            gyro_std=std[_GYRO],
            temperature_c=float(mean[_TEMPERATURE]),
            temperature_std_c=float(std[_TEMPERATURE]),
        )
