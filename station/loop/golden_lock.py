"""The station's golden-unit check and its lock, kept on disk so a restart keeps them.

``DATA_DIR/golden-STATION.json`` holds when the golden unit last agreed with its
reference and, while the station is locked, why. ``DATA_DIR/audit-STATION.jsonl`` is the
append-only record of every golden check, lock and unlock (one JSON object a line,
fsynced), with the supervisor and the reason of each unlock. A state file that cannot be
read locks the station: it cannot tell whether it was locked.

:class:`GoldenLock` answers the unit lifecycle (:mod:`station.loop.lifecycle`): what
stops a scanned serial (the lock, or the golden unit being due), whether a serial is
the golden unit, what the golden run's verdict means, and a supervisor's unlock.
"""

import json
import os
from datetime import UTC, datetime
from pathlib import Path
from uuid import UUID

from pydantic import BaseModel, ConfigDict, ValidationError

from station.domain.i18n import tr
from station.domain.quality.golden import GoldenUnit, disagreements, due
from station.domain.record.records import RunRecord
from station.results.files import disk_problem, write_atomic


class GoldenState(BaseModel):
    """What ``golden-STATION.json`` holds."""

    model_config = ConfigDict(extra="forbid")

    last_ok_at: datetime | None = None
    last_ok_run: UUID | None = None
    #: The lock's sentence, while the station is locked.
    locked: str | None = None
    locked_at: datetime | None = None
    locked_run: UUID | None = None


class GoldenLock:
    """The golden unit's schedule and the lock of one station."""

    def __init__(self, unit: GoldenUnit | None, data_dir: Path, station_id: str) -> None:
        self.unit = unit
        self.path = data_dir / f"golden-{station_id}.json"
        self.audit_path = data_dir / f"audit-{station_id}.jsonl"
        #: State and audit lines the disk refused: held here, written again at each look.
        self._unsaved: GoldenState | None = None
        self._unaudited: list[str] = []

    # -- state ----------------------------------------------------------------------

    def state(self) -> GoldenState:
        """The state on disk (read afresh: a supervisor's command may have changed it)."""
        if self._unsaved is not None or self._unaudited:
            self._flush()
        if self._unsaved is not None:
            return self._unsaved
        try:
            text = self.path.read_text(encoding="utf-8")
        except FileNotFoundError:
            return GoldenState()
        except OSError as exc:
            return self._unreadable(disk_problem(exc))
        except UnicodeDecodeError:
            return self._unreadable("it is not UTF-8 text")
        try:
            return GoldenState.model_validate_json(text)
        except ValidationError:
            return self._unreadable("it is not a golden state file")

    def _unreadable(self, why: str) -> GoldenState:
        return GoldenState(
            locked=f"LOCKED: golden state {self.path.name} unreadable ({why}): call a supervisor"
        )

    def _save(self, state: GoldenState) -> None:
        self._unsaved = state
        self._flush()

    def _audit(self, event: str, **fields: object) -> None:
        line = {"at": datetime.now(UTC).isoformat(), "event": event, **fields}
        self._unaudited.append(json.dumps(line, default=str, ensure_ascii=False) + "\n")
        self._flush()

    def _flush(self) -> None:
        """Write what is held; a disk that refuses keeps it held (a full disk never stops
        the line, and the lock holds in memory meanwhile)."""
        try:
            if self._unaudited:
                self.audit_path.parent.mkdir(parents=True, exist_ok=True)
                with self.audit_path.open("a", encoding="utf-8") as handle:
                    handle.write("".join(self._unaudited))
                    handle.flush()
                    os.fsync(handle.fileno())
                self._unaudited = []
            if self._unsaved is not None:
                write_atomic(self.path, self._unsaved.model_dump_json(indent=1) + "\n")
                self._unsaved = None
        except OSError:
            return

    # -- what the station asks -------------------------------------------------------

    def is_golden(self, serial: str) -> bool:
        """Whether ``serial`` is this station's golden unit."""
        return self.unit is not None and serial == self.unit.serial

    def line(self, now: datetime | None = None) -> str | None:
        """The line the screen shows: locked, or the golden unit due (None: neither)."""
        state = self.state()
        if state.locked:
            return state.locked
        if self.unit is not None and due(self.unit, state.last_ok_at, now or datetime.now(UTC)):
            return tr(
                "GOLDEN UNIT due: scan golden unit {serial} before the next unit "
                "(every {hours} h and at each shift start)",
                serial=self.unit.serial,
                hours=f"{self.unit.period_h:g}",
            )
        return None

    def refusal(self, serial: str, now: datetime | None = None) -> str | None:
        """Why ``serial`` may not be calibrated now (None: it may)."""
        line = self.line(now)
        if line is None:
            return None
        if line.startswith("LOCKED"):
            return line
        return None if self.is_golden(serial) else line

    # -- what happens ---------------------------------------------------------------

    def finish(self, record: RunRecord) -> str:
        """Judge the golden unit's run: agree (the check is done) or lock the station."""
        assert self.unit is not None
        found = disagreements(self.unit, record)
        state = self.state()
        serial = self.unit.serial
        if not found:
            state = state.model_copy(
                update={"last_ok_at": record.finished_at, "last_ok_run": record.run_id}
            )
            self._save(state)
            self._audit("golden_ok", serial=serial, run_id=str(record.run_id))
            return tr(
                "GOLDEN OK: golden unit {serial} agrees with its reference: go on", serial=serial
            )
        more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
        sentence = f"LOCKED: golden unit {serial} {found[0]}{more}: call a supervisor"
        state = state.model_copy(
            update={"locked": sentence, "locked_at": datetime.now(UTC), "locked_run": record.run_id}
        )
        self._save(state)
        self._audit("lock", serial=serial, run_id=str(record.run_id), disagreements=found)
        return sentence

    def unlock(self, supervisor: str, reason: str) -> str:
        """Unlock the station, recording who and why.

        The supervisor's unlock stands for this period's check: production goes on
        until the golden unit is next due.
        """
        state = self.state()
        if not state.locked:
            return tr("not locked: nothing to unlock")
        self._audit(
            "unlock",
            supervisor=supervisor,
            reason=reason,
            was=state.locked,
            locked_run=str(state.locked_run) if state.locked_run else None,
        )
        self._save(GoldenState(last_ok_at=datetime.now(UTC), last_ok_run=state.last_ok_run))
        return tr(
            "UNLOCKED by {supervisor}: {reason} (recorded in {file})",
            supervisor=supervisor,
            reason=reason,
            file=self.audit_path.name,
        )
