"""Rate-table / centrifuge logs: reading, validating and writing the CSV.

Columns (header names, any order; extra columns are ignored)::

    t                                    s
    rate_ref_x, rate_ref_y, rate_ref_z   deg/s, the reference rate
    acc_x, acc_y, acc_z                  g, the specific force on the unit
    gyro_x, gyro_y, gyro_z               deg/s, the gyro output
    segment                              optional: rows of one dwell share a label

One row per steady dwell, or one row per sample with a ``segment`` label: then every
segment is averaged to one dwell first (in order of first appearance). Any bad input
raises :class:`station.domain.errors.InputError` with one line naming the file, line and
column.
"""

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Final

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from station.domain.arrays import FloatArray
from station.domain.errors import InputError
from station.domain.sensors.sensor import AXES

RATE_COLUMNS: Final = tuple(f"rate_ref_{a}" for a in AXES)
ACC_COLUMNS: Final = tuple(f"acc_{a}" for a in AXES)
GYRO_COLUMNS: Final = tuple(f"gyro_{a}" for a in AXES)
NUMERIC_COLUMNS: Final = ("t", *RATE_COLUMNS, *ACC_COLUMNS, *GYRO_COLUMNS)
SEGMENT_COLUMN: Final = "segment"
#: Most dwells stored with a fit (a test plan has a few hundred).
MAX_STORED_DWELLS: Final = 20_000


@dataclass(frozen=True)
class GyroLog:
    """Dwells of a rate-table / centrifuge test: time (N,), rate, acc, gyro (N-by-3)."""

    t: FloatArray
    rate: FloatArray
    acc: FloatArray
    gyro: FloatArray

    def __len__(self) -> int:
        return int(self.t.shape[0])


class GyroDwells(BaseModel):
    """A log's dwells as plain lists, to store beside its fit (and plot it again later)."""

    model_config = ConfigDict(frozen=True, extra="forbid", allow_inf_nan=False)

    t: list[float] = Field(max_length=MAX_STORED_DWELLS)
    rate: list[tuple[float, float, float]] = Field(max_length=MAX_STORED_DWELLS)
    acc: list[tuple[float, float, float]] = Field(max_length=MAX_STORED_DWELLS)
    gyro: list[tuple[float, float, float]] = Field(max_length=MAX_STORED_DWELLS)

    @model_validator(mode="after")
    def _same_length(self) -> "GyroDwells":
        if not len(self.t) == len(self.rate) == len(self.acc) == len(self.gyro):
            raise ValueError("t, rate, acc and gyro need one entry per dwell each")
        return self

    @classmethod
    def of(cls, log: GyroLog) -> "GyroDwells":
        """The dwells of ``log``."""
        return cls(
            t=log.t.tolist(), rate=log.rate.tolist(), acc=log.acc.tolist(), gyro=log.gyro.tolist()
        )

    def to_log(self) -> GyroLog:
        """Back to arrays."""
        return GyroLog(
            t=np.array(self.t, dtype=np.float64),
            rate=np.array(self.rate, dtype=np.float64).reshape(-1, 3),
            acc=np.array(self.acc, dtype=np.float64).reshape(-1, 3),
            gyro=np.array(self.gyro, dtype=np.float64).reshape(-1, 3),
        )


def read_log(path: Path) -> GyroLog:
    """Read and validate a log; average each ``segment`` when that column is present."""
    try:
        with path.open(newline="", encoding="utf-8") as handle:
            reader = csv.reader(handle)
            header = next(reader, None)
            if header is None:
                raise InputError(f"{path}: empty file, expected a header line")
            names = [name.strip() for name in header]
            missing = [name for name in NUMERIC_COLUMNS if name not in names]
            if missing:
                raise InputError(f"{path}: missing column {', '.join(missing)}")
            index = [names.index(name) for name in NUMERIC_COLUMNS]
            segment_index = names.index(SEGMENT_COLUMN) if SEGMENT_COLUMN in names else None
            values: list[list[float]] = []
            segments: list[str] = []
            for row in reader:
                line = reader.line_num
                if not row or all(not cell.strip() for cell in row):
                    continue
                if len(row) < len(names):
                    raise InputError(
                        f"{path}:{line}: {len(row)} cells, the header has {len(names)}"
                    )
                values.append([_number(path, line, row[i], names[i]) for i in index])
                if segment_index is not None:
                    label = row[segment_index].strip()
                    if not label:
                        raise InputError(f"{path}:{line}: column segment: empty label")
                    segments.append(label)
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{path}: is a directory, expected a CSV file") from None
    except UnicodeDecodeError as exc:
        raise InputError(f"{path}: not a UTF-8 text file ({exc.reason})") from None
    table = np.array(values, dtype=np.float64).reshape(-1, len(NUMERIC_COLUMNS))
    if segment_index is not None:
        table = _average_segments(table, segments)
    return GyroLog(t=table[:, 0], rate=table[:, 1:4], acc=table[:, 4:7], gyro=table[:, 7:10])


def _number(path: Path, line: int, cell: str, column: str) -> float:
    try:
        value = float(cell)
    except ValueError:
        raise InputError(
            f"{path}:{line}: column {column}: {cell.strip()!r} is not a number"
        ) from None
    if not math.isfinite(value):
        raise InputError(f"{path}:{line}: column {column}: {cell.strip()!r} is not finite")
    return value


def _average_segments(table: FloatArray, segments: list[str]) -> FloatArray:
    labels, first, inverse = np.unique(np.array(segments), return_index=True, return_inverse=True)
    sums = np.zeros((labels.size, table.shape[1]))
    np.add.at(sums, inverse, table)
    means = sums / np.bincount(inverse, minlength=labels.size)[:, None]
    return means[np.argsort(first)]


def write_log(handle: IO[str], log: GyroLog, segments: list[str] | None = None) -> None:
    """Write ``log`` as CSV to ``handle`` (with a ``segment`` column when labels are given)."""
    table = np.column_stack([log.t, log.rate, log.acc, log.gyro])
    writer = csv.writer(handle, lineterminator="\n")
    writer.writerow([*NUMERIC_COLUMNS, *([SEGMENT_COLUMN] if segments is not None else [])])
    for k, row in enumerate(table):
        cells = [repr(float(v)) for v in row]
        writer.writerow(cells if segments is None else [*cells, segments[k]])
