"""The line's figures recomputed from its raw runs: a second implementation, for tests.

Written from the definitions of ``docs/report.md`` ("What the numbers mean"),
``docs/api.md`` (a unit's answer), never from the server's report code:

- an **attempt** is a production run the operator did not abort; an abort is a run,
  never an attempt;
- a unit's **first attempt** is its earliest attempt ever (by start time), its
  **latest** its latest attempt ever; a unit with nothing but aborts was never tested;
- a report's **units** are the units whose first attempt is among its selected runs;
  first-pass yield: of those, the units whose first attempt passed; final yield: the
  units whose latest attempt passed;
- **retests** are the selected attempts that are not their unit's first (a station's
  row: its own such attempts, so the rows add up to the total);
- a **capability** figure (mean, sd, Cp/Cpk, out of limits) is of one product's
  values against that product's own limits.

Everything is plain Python over :class:`Run` rows; floats as ``statistics`` gives them.
"""

import statistics
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from datetime import datetime
from typing import Any

#: The coefficients the report takes capability of, by the report's parameter names.
COEFFICIENTS = tuple(f"{family}_{axis}" for family in ("offset", "sensitivity") for axis in "xyz")


@dataclass(frozen=True)
class Run:
    """One stored run as the oracle needs it: identity, product, outcome, coefficients."""

    run_id: str
    serial: str
    station_id: str
    part_number: str
    started_at: datetime
    finished_at: datetime
    verdict: str
    aborted: bool
    #: ``offset_x`` … ``sensitivity_z``; empty for a run without coefficients.
    values: dict[str, float] = field(default_factory=dict)

    @property
    def attempt(self) -> bool:
        """An attempt: not the operator's abort."""
        return not self.aborted

    @property
    def passed(self) -> bool:
        return self.verdict == "pass"

    @classmethod
    def of_payload(cls, payload: dict[str, Any]) -> "Run":
        """The run a ``POST /api/v1/runs`` body describes."""
        coefficients = payload.get("coefficients") or {}
        values = {
            f"{family}_{axis}": float(value)
            for family in ("offset", "sensitivity")
            for axis, value in (coefficients.get(family) or {}).items()
        }
        return cls(
            run_id=payload["run_id"],
            serial=payload["serial"],
            station_id=payload["station_id"],
            part_number=payload["part_number"],
            started_at=datetime.fromisoformat(payload["started_at"]),
            finished_at=datetime.fromisoformat(payload["finished_at"]),
            verdict=payload["verdict"],
            aborted=any(f["code"] == "aborted" for f in payload["failures"]),
            values=values,
        )


@dataclass(frozen=True)
class Selection:
    """A report's filter: product, station, and ``since`` (inclusive) to ``until``
    (exclusive) on a run's start."""

    part_number: str | None = None
    station_id: str | None = None
    since: datetime | None = None
    until: datetime | None = None

    def holds(self, run: Run) -> bool:
        return (
            (self.part_number is None or run.part_number == self.part_number)
            and (self.station_id is None or run.station_id == self.station_id)
            and (self.since is None or run.started_at >= self.since)
            and (self.until is None or run.started_at < self.until)
        )


@dataclass(frozen=True)
class Counts:
    """A report's summary counts and yields (``Summary`` of the report's JSON)."""

    runs: int
    runs_passed: int
    units_tested: int
    units_passed: int
    units_failed: int
    first_pass_units: int
    retests: int
    aborted_runs: int

    @property
    def report_yield(self) -> float | None:
        return _ratio(self.runs_passed, self.runs)

    @property
    def first_pass_yield(self) -> float | None:
        return _ratio(self.first_pass_units, self.units_tested)

    @property
    def final_yield(self) -> float | None:
        return _ratio(self.units_passed, self.units_tested)

    @property
    def retest_rate(self) -> float | None:
        return _ratio(self.retests, self.units_tested)

    def figures(self) -> dict[str, float | int | None]:
        """The counts and the yields, by the report JSON's names."""
        ratios = ("report_yield", "first_pass_yield", "final_yield", "retest_rate")
        return {**self.__dict__, **{name: getattr(self, name) for name in ratios}}


@dataclass(frozen=True)
class Capability:
    """One parameter's figures over one product's values against its limits."""

    count: int
    mean: float | None
    std: float | None
    cp: float | None
    cpk: float | None
    out_of_limits: int

    @classmethod
    def of(cls, values: Sequence[float], lower: float | None, upper: float | None) -> "Capability":
        """Mean and sample sd of ``values``; ``Cp = (U − L)/6σ``,
        ``Cpk = min(U − μ, μ − L)/3σ`` (one side: that side's term; no Cp); values
        strictly outside ``[L, U]`` are out of limits."""
        n = len(values)
        mean = statistics.fmean(values) if n else None
        std = statistics.stdev(values) if n >= 2 else None
        cp = cpk = None
        if mean is not None and std:
            if lower is not None and upper is not None:
                cp = (upper - lower) / (6 * std)
            sides = [
                s
                for s in (
                    None if upper is None else upper - mean,
                    None if lower is None else mean - lower,
                )
                if s is not None
            ]
            cpk = min(sides) / (3 * std) if sides else None
        out = sum(
            1
            for v in values
            if (lower is not None and v < lower) or (upper is not None and v > upper)
        )
        return cls(n, mean, std, cp, cpk, out)


@dataclass(frozen=True)
class UnitAnswer:
    """What ``GET /api/v1/units/{serial}`` must say of a unit (``docs/api.md``)."""

    verdict: str
    attempts: int
    latest_run_id: str
    holds_run_id: str | None


def _ratio(part: int, whole: int) -> float | None:
    return part / whole if whole else None


def _order(run: Run) -> tuple[datetime, str]:
    return (run.started_at, run.run_id)


class Line:
    """Every run the line stored, and the figures the definitions give over them."""

    def __init__(self, runs: Iterable[Run] = ()) -> None:
        self.runs: list[Run] = list(runs)

    def add(self, run: Run) -> None:
        self.runs.append(run)

    def history(self, serial: str) -> list[Run]:
        """The unit's runs, oldest first."""
        return sorted((r for r in self.runs if r.serial == serial), key=_order)

    def attempts(self, serial: str) -> list[Run]:
        """The unit's attempts (aborts aside), oldest first."""
        return [r for r in self.history(serial) if r.attempt]

    def first_attempts(self) -> dict[str, Run]:
        """Each tested unit's first attempt ever."""
        firsts: dict[str, Run] = {}
        for run in sorted((r for r in self.runs if r.attempt), key=_order):
            firsts.setdefault(run.serial, run)
        return firsts

    def latest_attempts(self) -> dict[str, Run]:
        """Each tested unit's latest attempt ever."""
        return {r.serial: r for r in sorted((r for r in self.runs if r.attempt), key=_order)}

    def counts(self, selection: Selection = Selection()) -> Counts:
        """The summary of the runs ``selection`` holds."""
        chosen = [r for r in self.runs if selection.holds(r)]
        firsts = self.first_attempts()
        latest = self.latest_attempts()
        first_ids = {r.run_id for r in firsts.values()}
        units = [r.serial for r in chosen if r.run_id in first_ids]
        passed = sum(1 for serial in units if latest[serial].passed)
        return Counts(
            runs=len(chosen),
            runs_passed=sum(1 for r in chosen if r.passed),
            units_tested=len(units),
            units_passed=passed,
            units_failed=len(units) - passed,
            first_pass_units=sum(1 for serial in units if firsts[serial].passed),
            retests=sum(1 for r in chosen if r.attempt and r.run_id not in first_ids),
            aborted_runs=sum(1 for r in chosen if r.aborted),
        )

    def stations(self, selection: Selection = Selection()) -> dict[str, Counts]:
        """Per station with runs in ``selection``: the summary of its own runs there."""
        names = {r.station_id for r in self.runs if selection.holds(r)}
        return {s: self.counts(_narrowed(selection, station_id=s)) for s in names}

    def products(self, selection: Selection = Selection()) -> dict[str, Counts]:
        """Per part number with runs in ``selection``: the summary of its runs there."""
        names = {r.part_number for r in self.runs if selection.holds(r)}
        return {p: self.counts(_narrowed(selection, part_number=p)) for p in names}

    def values(self, parameter: str, selection: Selection) -> list[float]:
        """``parameter``'s value of every selected run that has coefficients."""
        return [r.values[parameter] for r in self.runs if selection.holds(r) and r.values]

    def capability(
        self, parameter: str, selection: Selection, limits: tuple[float | None, float | None]
    ) -> Capability:
        """``parameter``'s figures over the selected runs (one product's) against ``limits``."""
        return Capability.of(self.values(parameter, selection), *limits)

    def held_units(self) -> set[str]:
        """Units whose latest attempt failed (on hold), any day."""
        return {s for s, r in self.latest_attempts().items() if not r.passed}

    def unit(self, serial: str) -> UnitAnswer:
        """The unit's answer: the verdict of its latest attempt (of its latest run when
        every run was an abort), its attempts, its latest run (aborts too) and the last
        run that wrote it (an attempt with coefficients)."""
        history = self.history(serial)
        attempts = [r for r in history if r.attempt]
        wrote = [r for r in attempts if r.values]
        return UnitAnswer(
            verdict=(attempts or history)[-1].verdict,
            attempts=len(attempts),
            latest_run_id=history[-1].run_id,
            holds_run_id=wrote[-1].run_id if wrote else None,
        )


def _narrowed(selection: Selection, **changes: str) -> Selection:
    return Selection(**{**selection.__dict__, **changes})
