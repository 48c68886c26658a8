"""The station's checks on itself: the golden unit and its lock, and the drift warning.

:class:`ShiftChecks` is what the unit lifecycle (:mod:`station.loop.lifecycle`) calls:
at a scan (:meth:`ShiftChecks.at_scan`: a supervisor's ``unlock``, a station locked or
waiting for its golden unit, the golden unit itself), at a verdict
(:meth:`ShiftChecks.at_verdict`: a golden run is judged, a production run feeds the
drift watch), and for the screen (:meth:`ShiftChecks.lines`).

A supervisor unlocks at the serial prompt by typing ``unlock NAME REASON…`` (the name
without spaces, then the reason in words); the unlock is recorded with both in the
audit file (:mod:`station.loop.golden_lock`).
"""

from dataclasses import dataclass
from pathlib import Path

from station.domain.i18n import tr
from station.domain.quality.golden import GoldenUnit
from station.domain.record.records import RunRecord
from station.loop.drift_watch import DriftWatch
from station.loop.golden_lock import GoldenLock


def unlock_usage() -> str:
    """How a supervisor unlocks the station, said when the unlock lacks a word."""
    return tr(
        "unlock needs a name and a reason: unlock NAME REASON (e.g. unlock j.smith jig reseated)"
    )


@dataclass(frozen=True)
class AtScan:
    """What a scanned line means: ``said`` (None: a unit to calibrate) and ``golden``."""

    said: str | None = None
    golden: bool = False


class ShiftChecks:
    """The golden unit, the lock and the drift watch of one station."""

    def __init__(self, golden: GoldenUnit | None, data_dir: Path, station_id: str) -> None:
        self.golden = GoldenLock(golden, data_dir, station_id)
        self.drift = DriftWatch(data_dir, station_id)

    def lines(self) -> list[str]:
        """The lines the screen shows under the header (key words first)."""
        return [line for line in (self.golden.line(), self.drift.line) if line]

    def at_scan(self, text: str) -> AtScan:
        """A supervisor's unlock, a refusal, or the unit to calibrate (golden or not)."""
        words = text.split()
        if words and words[0].lower() == "unlock":
            if len(words) < 3:
                return AtScan(unlock_usage())
            return AtScan(self.golden.unlock(words[1], " ".join(words[2:])))
        refusal = self.golden.refusal(text)
        if refusal is not None:
            return AtScan(refusal)
        return AtScan(golden=self.golden.is_golden(text))

    def at_verdict(self, record: RunRecord) -> str | None:
        """The line to say about a finished run, if any: the golden unit's run judged
        against its reference, a production run fed to the drift watch."""
        if record.purpose == "golden":
            if record.failures and all(f.code == "aborted" for f in record.failures):
                return tr("golden unit aborted: it is still due")
            return self.golden.finish(record)
        return self.drift.add(record)
