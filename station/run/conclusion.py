"""The end of a run: its verdict (the failures found, then the limit checks) and record.

A pure function of what the run holds, so that :class:`station.run.unit_run.UnitRun` only
decides *when* the run ends.
"""

from dataclasses import dataclass

from station.domain.calibration import Solution
from station.domain.limits import LimitsProfile
from station.domain.records import PoseRecord, RunRecord
from station.domain.run_settings import RunSettings
from station.results.journal import RunJournal
from station.run import record
from station.run.gyro import LiveGyro
from station.run.verdict import Failures


@dataclass(frozen=True)
class Conclusion:
    """The verification pose's error (mg, when checked) and the run's record (None
    when nothing is to be stored)."""

    verification_error_mg: float | None
    record: RunRecord | None


def conclude(
    journal: RunJournal,
    settings: RunSettings,
    profile: LimitsProfile,
    solution: Solution | None,
    failures: Failures,
    *,
    evidence: PoseRecord | None,
    gyro: LiveGyro | None,
    store: bool,
) -> Conclusion:
    """The verdict of the run and, if ``store``, its record.

    ``evidence`` is the live window that failed the unit before its pose was captured;
    ``gyro`` the gyro matrix of a whole-unit run, whose limit checks join the others.
    """
    captures = journal.captures
    fit_count = len(settings.poses)
    summary = record.gyro_summary(captures, fit_count, solution)
    for reason in gyro.checks(profile) if gyro is not None else ():
        failures.add(reason)
    verdict = failures.final(profile, captures, solution, fit_count, summary)
    if not store:
        return Conclusion(verdict.verification_error_mg, None)
    run = record.run_record(
        journal,
        settings,
        profile,
        solution,
        failures=verdict.reasons,
        verification_error_mg=verdict.verification_error_mg,
        gyro=summary,
        poses=record.pose_records(captures, evidence),
        gyro_matrix=gyro.record() if gyro is not None else None,
    )
    return Conclusion(verdict.verification_error_mg, run)
