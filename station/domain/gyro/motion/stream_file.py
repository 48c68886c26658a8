"""Reading a recorded stream: CSV with the header ``t,ax,ay,az,gx,gy,gz``.

``t`` in seconds (any rate, increasing), ``ax, ay, az`` raw accelerometer ADC counts,
``gx, gy, gz`` raw gyro rates in deg/s, one sample a row; an optional ``temp_c`` column,
the sensor's temperature in °C (the uncertainty budget's temperature term); other
columns are ignored.
The numbers are parsed in one vectorised pass (memory linear in the rows); when that
fails, the file is scanned again to name the first bad line.
"""

import csv
from pathlib import Path
from typing import TYPE_CHECKING, Final

import numpy as np

from station.domain.errors import InputError
from station.domain.gyro.motion.stream import RecordedStream

if TYPE_CHECKING:
    from _csv import Reader

COLUMNS: Final = ("t", "ax", "ay", "az", "gx", "gy", "gz")
#: Optional: the sensor's temperature, °C.
TEMPERATURE_COLUMN: Final = "temp_c"


def read_stream_file(path: Path) -> RecordedStream:
    """The stream recorded in ``path``.

    Raises:
        InputError: a missing or unreadable file, a header without the columns, a cell
            that is not a number or a short row (naming its line), no samples.
        StreamError: time that does not increase (from :class:`RecordedStream`).
    """
    try:
        with path.open(encoding="utf-8-sig", newline="") as handle:
            header, header_line = _header(path, csv.reader(handle))
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read: {exc}") from None
    missing = [c for c in COLUMNS if c not in header]
    if missing:
        raise InputError(
            f"{path}:{header_line}: header lacks column(s) {','.join(missing)} "
            f"(found: {','.join(header)}); expected {','.join(COLUMNS)}"
        )
    columns = COLUMNS + ((TEMPERATURE_COLUMN,) if TEMPERATURE_COLUMN in header else ())
    index = [header.index(c) for c in columns]
    try:
        data = np.loadtxt(
            path,
            delimiter=",",
            skiprows=header_line,
            usecols=index,
            ndmin=2,
            encoding="utf-8-sig",
            dtype=np.float64,
        )
    except (ValueError, UnicodeDecodeError):
        raise InputError(_first_bad_line(path, columns, index, len(header))) from None
    if not len(data):
        raise InputError(f"{path}: no samples after the header")
    if not np.isfinite(data).all():
        row = int(np.argmax(~np.isfinite(data).all(axis=1)))
        raise InputError(f"{path}: data row {row + 1}: a value is not a finite number")
    return RecordedStream(
        t=data[:, 0],
        accel_counts=data[:, 1:4],
        gyro_dps=data[:, 4:7],
        temperature_c=data[:, 7] if len(columns) > len(COLUMNS) else None,
    )


def _header(path: Path, reader: "Reader") -> tuple[list[str], int]:
    for row in reader:
        if any(cell.strip() for cell in row):
            return [cell.strip().lower() for cell in row], reader.line_num
    raise InputError(f"{path}: the file is empty; expected a header {','.join(COLUMNS)}")


def _first_bad_line(path: Path, columns: tuple[str, ...], index: list[int], width: int) -> str:
    """The first line numpy could not read, named with its problem."""
    with path.open(encoding="utf-8-sig", errors="replace", newline="") as handle:
        reader = csv.reader(handle)
        _header(path, reader)
        for row in reader:
            if not any(cell.strip() for cell in row):
                continue
            where = f"{path}:{reader.line_num}"
            if len(row) < max(index) + 1:
                return f"{where}: {len(row)} cells, the header has {width}"
            for column, i in zip(columns, index, strict=True):
                cell = row[i].strip()
                try:
                    float(cell)
                except ValueError:
                    shown = repr(cell) if cell else "an empty cell"
                    return f"{where}: column {column}: {shown} is not a number"
    return f"{path}: not a CSV of numbers under the header"
