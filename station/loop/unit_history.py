"""A unit's history at the station: what to ask at the scan, where it goes at the verdict.

At the scan the station gathers the unit's runs from its store and from its outbox (runs
not yet delivered count too). A unit that passed already is not calibrated again without
the operator saying so ("PT000123 passed at 10:42 on line1-st2: calibrate again? y/n");
a unit that has used up its attempts (the limits profile's retest limit) goes to rework
instead. When the store cannot be reached the operator is told the history is
unavailable and goes on. The same runs decide where the unit goes after its verdict
(:func:`station.domain.unit_state.disposition`, in the run's record).
"""

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import datetime
from enum import StrEnum
from pathlib import Path

from pydantic import ValidationError

from station.domain.records import RunRecord, RunSummary
from station.domain.unit_state import UnitCalibration
from station.results.storage import RunStore, StoreError

Run = RunRecord | RunSummary


class ScanAction(StrEnum):
    """What the station does with a scanned serial number."""

    START = "start"
    CONFIRM = "confirm"
    REFUSE = "refuse"


@dataclass(frozen=True)
class ScanDecision:
    """The action and what to tell the operator (``note``: said whatever the action)."""

    action: ScanAction
    text: str | None = None
    note: str | None = None


def local_time(moment: datetime, now: datetime | None = None) -> str:
    """``10:42`` today, else ``2026-11-02 10:42``, in the station's local time."""
    here = moment.astimezone()
    today = (now or datetime.now().astimezone()).date()
    return here.strftime("%H:%M" if here.date() == today else "%Y-%m-%d %H:%M")


@dataclass(frozen=True)
class UnitHistory:
    """The unit's runs known to the station, oldest first."""

    serial: str
    runs: tuple[Run, ...] = ()
    #: Why the store's part is missing (None: the store answered).
    unavailable: str | None = None

    @classmethod
    def gather(cls, serial: str, store: RunStore | None, waiting: Sequence[Path]) -> "UnitHistory":
        """The runs of ``serial`` in ``store`` and in the outbox files ``waiting``."""
        runs: dict[str, Run] = {}
        unavailable = None
        if store is None:
            unavailable = "results database unreachable"
        else:
            try:
                runs.update((str(r.run_id), r) for r in store.history(serial))
            except StoreError as exc:
                unavailable = str(exc)
        for path in waiting:
            try:
                text = path.read_text(encoding="utf-8")
                if serial in text:
                    record = RunRecord.model_validate_json(text)
                    if record.serial == serial:
                        runs.setdefault(str(record.run_id), record)
            except (OSError, UnicodeDecodeError, ValidationError):
                continue  # the outbox sets such files aside; they are no history
        ordered = sorted(runs.values(), key=lambda r: (r.started_at, str(r.run_id)))
        return cls(serial, tuple(ordered), unavailable)

    def at_scan(self, attempts_allowed: int) -> ScanDecision:
        """Start, ask first (it passed already), or refuse (no attempts left)."""
        note = (
            f"history of {self.serial} unavailable ({self.unavailable}): going on"
            if self.unavailable
            else None
        )
        if not self.runs:
            return ScanDecision(ScanAction.START, note=note)
        state = UnitCalibration.of_history(self.runs)
        used = state.attempts >= attempts_allowed
        if state.verdict == "pass" and state.holds is not None:
            passed = (
                f"{self.serial} passed at {local_time(state.holds.written_at)} "
                f"on {state.holds.station_id}"
            )
            if used:
                text = (
                    f"{passed} and has had {state.attempts} attempts, the limit: "
                    "ship it as it is, or send it to rework"
                )
                return ScanDecision(ScanAction.REFUSE, text, note)
            return ScanDecision(ScanAction.CONFIRM, f"{passed}: calibrate again? y/n", note)
        if used:
            text = (
                f"{self.serial} has failed {state.attempts} attempts "
                f"(limit {attempts_allowed}): send it to rework, it is not calibrated again"
            )
            return ScanDecision(ScanAction.REFUSE, text, note)
        return ScanDecision(ScanAction.START, note=note)
