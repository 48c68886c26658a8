"""The station's own recent units, and the drift warning computed from them.

``DATA_DIR/recent-STATION.json`` keeps the coefficients of the last passed production
units this station calibrated (golden runs are not production), oldest first, so a
restart keeps the history the statistic needs. After every such unit the station looks
for a common trend over the last :data:`~station.domain.quality.drift.DRIFT_WINDOW` units
(:func:`station.domain.quality.drift.find_drift`) and shows one line while it lasts.
"""

import contextlib
from pathlib import Path

from pydantic import BaseModel, ConfigDict, ValidationError

from station.domain.quality.drift import DRIFT_WINDOW, find_drift
from station.domain.record.records import RunRecord
from station.results.files import write_atomic

#: Units kept on disk (the statistic reads the last DRIFT_WINDOW of them).
KEPT = 50


class RecentUnit(BaseModel):
    """One passed unit's coefficients."""

    model_config = ConfigDict(extra="forbid")

    serial: str
    offset: tuple[float, float, float]
    sensitivity: tuple[float, float, float]


class Recent(BaseModel):
    """What ``recent-STATION.json`` holds."""

    model_config = ConfigDict(extra="forbid")

    units: list[RecentUnit] = []


class DriftWatch:
    """The recent units of one station and whether they drift."""

    def __init__(self, data_dir: Path, station_id: str, window: int = DRIFT_WINDOW) -> None:
        self.path = data_dir / f"recent-{station_id}.json"
        self.window = window
        self.recent = self._load()
        #: The warning shown now (None: no drift found).
        self.line: str | None = self._judge()

    def _load(self) -> Recent:
        try:
            return Recent.model_validate_json(self.path.read_text(encoding="utf-8"))
        except (OSError, ValidationError, UnicodeDecodeError):
            return Recent()  # no history yet, or none readable: it builds up again

    def _judge(self) -> str | None:
        units = self.recent.units
        drift = find_drift(
            [u.offset for u in units], [u.sensitivity for u in units], window=self.window
        )
        return None if drift is None else drift.sentence

    def add(self, record: RunRecord) -> str | None:
        """Take in a finished production run; the warning, if its units now drift."""
        if record.verdict != "pass" or record.coefficients is None:
            return self.line
        unit = RecentUnit(
            serial=record.serial,
            offset=record.coefficients.offset.as_tuple(),
            sensitivity=record.coefficients.sensitivity.as_tuple(),
        )
        self.recent.units = [*self.recent.units, unit][-KEPT:]
        # A disk that refuses keeps the history in memory; the disk's own line says so.
        with contextlib.suppress(OSError):
            write_atomic(self.path, self.recent.model_dump_json() + "\n")
        self.line = self._judge()
        return self.line
