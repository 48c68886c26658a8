"""Reading pose files: CSV with a header holding ``ax,ay,az``, one still pose a row.

Optional columns ``sx,sy,sz`` (each pose's sample standard deviation, counts) and ``n``
(its sample count) feed the uncertainty budget's pose noise; without them the budget
assumes the sensor's (:mod:`station.domain.calibration.uncertainty`). An optional column
``temp_c`` (the sensor's temperature while the pose was taken, °C) feeds its temperature
term; without it the drift across the poses is named as not in U. Other columns are
ignored; blank lines are skipped. Every problem is reported as an
:class:`station.domain.errors.InputError` naming the file and, where one applies, the line.
"""

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.errors import InputError

COLUMNS = ("ax", "ay", "az")
#: Optional: each pose's sample standard deviation per axis (counts) and sample count.
SPREAD_COLUMNS = ("sx", "sy", "sz", "n")
#: Optional: the sensor's temperature at each pose, °C.
TEMPERATURE_COLUMN = "temp_c"


@dataclass(frozen=True, eq=False)
class PoseFile:
    """Pose means (N, 3) counts and the file line each came from; with the optional
    columns, each pose's sample spread (N, 3) counts and sample count (N,), and its
    temperature (N,) °C."""

    path: Path
    poses: FloatArray
    lines: tuple[int, ...]
    spread: FloatArray | None = None
    samples: FloatArray | None = None
    temperatures: FloatArray | None = None

    def where(self, pose: int | None) -> str:
        """``FILE:LINE`` of a pose (0-based index), or ``FILE`` for the whole set."""
        return f"{self.path}:{self.lines[pose]}" if pose is not None else str(self.path)


def read_pose_file(path: Path) -> PoseFile:
    """Read the pose means of ``path``.

    Raises:
        InputError: the file is missing or unreadable, has no ``ax,ay,az`` header,
            a cell that is not a number, or no pose rows.
    """
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read: {exc}") from None

    reader = csv.reader(text.splitlines())
    header = next((row for row in reader if any(cell.strip() for cell in row)), None)
    if header is None:
        raise InputError(f"{path}: the file is empty; expected a header with ax,ay,az")
    names = [cell.strip().lower() for cell in header]
    missing = [c for c in COLUMNS if c not in names]
    if missing:
        raise InputError(
            f"{path}:{reader.line_num}: header lacks column(s) {','.join(missing)} "
            f"(found: {','.join(names)})"
        )
    present = [c for c in SPREAD_COLUMNS if c in names]
    if present and len(present) < len(SPREAD_COLUMNS):
        lacking = ",".join(c for c in SPREAD_COLUMNS if c not in names)
        raise InputError(
            f"{path}:{reader.line_num}: header has {','.join(present)} but lacks {lacking}: "
            "a pose's spread needs sx,sy,sz and its sample count n"
        )
    warm = (TEMPERATURE_COLUMN,) if TEMPERATURE_COLUMN in names else ()
    columns = COLUMNS + (SPREAD_COLUMNS if present else ()) + warm
    index = [names.index(c) for c in columns]

    rows: list[list[float]] = []
    lines: list[int] = []
    for row in reader:
        if not any(cell.strip() for cell in row):
            continue
        values = []
        for column, i in zip(columns, index, strict=True):
            cell = row[i].strip() if i < len(row) else ""
            try:
                value = float(cell)
            except ValueError:
                shown = repr(cell) if cell else "an empty cell"
                raise InputError(
                    f"{path}:{reader.line_num}: column {column}: {shown} is not a number"
                ) from None
            if column in SPREAD_COLUMNS and not (0.0 <= value < float("inf")):
                raise InputError(
                    f"{path}:{reader.line_num}: column {column}: {cell} is not a spread "
                    "or count (a finite number ≥ 0)"
                )
            if column == TEMPERATURE_COLUMN and not (-273.15 < value < float("inf")):
                raise InputError(
                    f"{path}:{reader.line_num}: column {column}: {cell} is not a temperature "
                    "(a finite number of °C above absolute zero)"
                )
            if column == "n" and (value < 1 or value != int(value)):
                raise InputError(
                    f"{path}:{reader.line_num}: column n: {cell} is not a sample count "
                    "(a whole number ≥ 1)"
                )
            values.append(value)
        rows.append(values)
        lines.append(reader.line_num)
    if not rows:
        raise InputError(f"{path}: no pose rows after the header")
    table = np.array(rows, dtype=np.float64)
    temperatures = table[:, -1] if warm else None
    spread, samples = (table[:, 3:6], table[:, 6]) if present else (None, None)
    return PoseFile(path, table[:, :3], tuple(lines), spread, samples, temperatures)
