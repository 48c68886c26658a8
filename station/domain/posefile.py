"""Reading pose files: CSV with a header holding ``ax,ay,az``, one still pose a row.

Other columns are ignored; blank lines are skipped. Every problem is reported as an
:class:`station.domain.errors.InputError` naming the file and, where one applies, the line.
"""

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.errors import InputError

COLUMNS = ("ax", "ay", "az")


@dataclass(frozen=True, eq=False)
class PoseFile:
    """Pose means (N, 3) counts and the file line each came from."""

    path: Path
    poses: FloatArray
    lines: tuple[int, ...]

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
    index = [names.index(c) for c in COLUMNS]

    rows: list[list[float]] = []
    lines: list[int] = []
    for row in reader:
        if not any(cell.strip() for cell in row):
            continue
        values = []
        for column, i in zip(COLUMNS, index, strict=True):
            cell = row[i].strip() if i < len(row) else ""
            try:
                values.append(float(cell))
            except ValueError:
                shown = repr(cell) if cell else "an empty cell"
                raise InputError(
                    f"{path}:{reader.line_num}: column {column}: {shown} is not a number"
                ) from None
        rows.append(values)
        lines.append(reader.line_num)
    if not rows:
        raise InputError(f"{path}: no pose rows after the header")
    return PoseFile(path, np.array(rows, dtype=np.float64), tuple(lines))
