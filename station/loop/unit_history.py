"""A unit's history at the station: what to ask at the scan, where it goes at the verdict.

At the scan the station gathers the unit's runs from its store and from its outbox (runs
not yet delivered count too), and its quality reviews. A unit that passed already is not
calibrated again without the operator saying so ("PT000123 passed at 10:42 on line1-st2:
calibrate again? y/n"); a unit that has used up its attempts (the limits profile's
retest limit) goes to rework instead. A unit sent to rework is refused until a quality
review releases it for a retest (its attempts then count afresh); a scrapped unit is
refused for good. When the store cannot be reached the operator is told the history is
unavailable and goes on. The same runs decide where the unit goes after its verdict
(:func:`station.domain.record.unit_state.disposition`, in the run's record).
"""

from collections.abc import Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from enum import StrEnum
from pathlib import Path

from pydantic import ValidationError

from station.domain.constants import DEFAULT_PART_NUMBER
from station.domain.i18n import tr
from station.domain.quality.days import wall_clock
from station.domain.record.records import HoldReview, RunRecord, RunSummary
from station.domain.record.unit_state import UnitCalibration, deciding_review
from station.results.outbox_files import UnreadableRecordError, read_bytes
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
    """``10:42`` today, else ``2026-11-02 10:42``, in the station's local time (in UTC,
    saying so, where that would leave the years 1…9999: a clock set wrong)."""
    here = wall_clock(moment)
    today = (now or datetime.now().astimezone()).date()
    shown = f"{here:%H:%M}" if here.date() == today else f"{here.date().isoformat()} {here:%H:%M}"
    return f"{shown} UTC" if here.tzinfo is UTC else shown


@dataclass(frozen=True)
class UnitHistory:
    """The unit's runs known to the station, oldest first."""

    serial: str
    runs: tuple[Run, ...] = ()
    #: Why the store's part is missing (None: the store answered).
    unavailable: str | None = None
    #: The unit's quality reviews, oldest first.
    reviews: tuple[HoldReview, ...] = ()

    @classmethod
    def gather(cls, serial: str, store: RunStore | None, waiting: Sequence[Path]) -> "UnitHistory":
        """The runs of ``serial`` in ``store`` and in the outbox files ``waiting``."""
        runs: dict[str, Run] = {}
        reviews: tuple[HoldReview, ...] = ()
        unavailable = None
        if store is None:
            unavailable = "results database unreachable"
        else:
            try:
                runs.update((str(r.run_id), r) for r in store.history(serial))
                reviews = tuple(store.reviews(serial))
            except StoreError as exc:
                unavailable = str(exc)
        for path in waiting:
            try:
                text = read_bytes(path).decode("utf-8")
                if serial in text:
                    record = RunRecord.model_validate_json(text)
                    if record.serial == serial:
                        runs.setdefault(str(record.run_id), record)
            except (UnreadableRecordError, UnicodeDecodeError, ValidationError):
                continue  # the outbox sets such files aside; they are no history
        ordered = sorted(runs.values(), key=lambda r: (r.started_at, str(r.run_id)))
        return cls(serial, tuple(ordered), unavailable, reviews)

    @property
    def decided(self) -> HoldReview | None:
        """The latest review, if it came after the unit's latest run: it decides."""
        return deciding_review(self.runs, self.reviews)

    @property
    def counted(self) -> tuple[Run, ...]:
        """The runs that count now: those after the latest release for a retest."""
        released = [r.reviewed_at for r in self.reviews if r.decision == "retest"]
        if not released:
            return self.runs
        return tuple(r for r in self.runs if r.started_at > released[-1])

    def at_scan(
        self, attempts_allowed: int, part_number: str = DEFAULT_PART_NUMBER
    ) -> ScanDecision:
        """Start, ask first (it passed already), or refuse (scrapped, sent to rework and
        not released, no attempts left, calibrated as another product than
        ``part_number``, the station's)."""
        note = (
            tr(
                "history of {serial} unavailable ({why}): going on",
                serial=self.serial,
                why=self.unavailable,
            )
            if self.unavailable
            else None
        )
        if self.runs and self.runs[-1].part_number != part_number:
            text = tr(
                "{serial} was calibrated as {before}, scanned as {part_number}: set it aside "
                "for its own product's station; nothing was recorded",
                serial=self.serial,
                before=self.runs[-1].part_number,
                part_number=part_number,
            )
            return ScanDecision(ScanAction.REFUSE, text, note)
        decided = self.decided
        if decided is not None and decided.decision == "scrap":
            text = tr(
                "{serial} was scrapped by {reviewer} on {time} ({cause}): it is not "
                "calibrated again",
                serial=self.serial,
                reviewer=decided.reviewer,
                time=local_time(decided.reviewed_at),
                cause=decided.root_cause,
            )
            return ScanDecision(ScanAction.REFUSE, text, note)
        runs = self.counted
        if not runs:
            return ScanDecision(ScanAction.START, note=note)
        state = UnitCalibration.of_history(runs)
        used = state.attempts >= attempts_allowed
        if state.verdict == "pass" and state.holds is not None:
            passed = tr(
                "{serial} passed at {time} on {station}",
                serial=self.serial,
                time=local_time(state.holds.written_at),
                station=state.holds.station_id,
            )
            if used:
                text = tr(
                    "{passed} and has had {attempts} attempts, the limit: "
                    "ship it as it is, or send it to rework",
                    passed=passed,
                    attempts=state.attempts,
                )
                return ScanDecision(ScanAction.REFUSE, text, note)
            return ScanDecision(
                ScanAction.CONFIRM, tr("{passed}: calibrate again? y/n", passed=passed), note
            )
        if used:
            text = tr(
                "{serial} has failed {attempts} attempts "
                "(limit {limit}): send it to rework, it is not calibrated again",
                serial=self.serial,
                attempts=state.attempts,
                limit=attempts_allowed,
            )
            return ScanDecision(ScanAction.REFUSE, text, note)
        if runs[-1].disposition == "rework":
            failed = ", ".join(f.code for f in runs[-1].failures) or tr("failed")
            text = tr(
                "{serial} was sent to rework at {time} ({failed}): it is not calibrated "
                "until a quality review releases it (calstation review {serial} --decision "
                "retest …)",
                serial=self.serial,
                time=local_time(runs[-1].finished_at),
                failed=failed,
            )
            return ScanDecision(ScanAction.REFUSE, text, note)
        return ScanDecision(ScanAction.START, note=note)
