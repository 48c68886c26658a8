"""The verdict of one unit's run, reached in one place, and the run's record built once.

A run's failures are those found while it went, in the order found (a saturated axis,
a failed solve or write-back, the unit's own output, the gyro matrix), then the limit
checks of what it measured (:func:`station.domain.product.judging.limit_checks`, which the
report's what-if uses too): every pose's noise and link loss, the offsets and
sensitivities, the verification pose's calibrated |g|, the gyro biases and the gyro
matrix K, each against the limits profile (by its decision rule where the value carries
its U), and the record names the rule that judged each limit. An abort replaces
whatever was found and is not checked: it says nothing about the unit. An abort after
the write-back is not recorded as an abort: the unit holds the coefficients, and its
own output was not checked.

The record (:func:`conclude`) carries, from the start, where the unit goes next
(:func:`station.domain.record.unit_state.disposition`, from its earlier runs) and what the run
was for (the station's golden unit, or production).
"""

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from station.domain.calibration import CalibrationError, Solution, apply
from station.domain.gyro.motion import GyroMatrixFit
from station.domain.product.judging import (
    Measured,
    check_rules,
    limit_checks,
    uncertainty_of,
    verdict_failures,
)
from station.domain.product.limits import LimitsProfile
from station.domain.product.run_settings import RunSettings
from station.domain.record.records import (
    Disposition,
    FailureReason,
    GyroMatrixRecord,
    GyroSummary,
    PoseRecord,
    RunRecord,
    UncertaintyRecord,
    Verdict,
)
from station.domain.record.unit_state import Run, disposition
from station.results.journal import Capture, RunJournal
from station.run import record

#: Longest failure message kept (the record's limit is 500 characters).
MESSAGE_MAX = 300


def saturated(axes: tuple[str, ...], pose: int) -> FailureReason:
    """Accelerometer ``axes`` sat at an ADC rail while the unit lay still in ``pose``."""
    return FailureReason(
        code="saturated",
        message=f"accelerometer {', '.join(axes)} stuck at the ADC rail while the unit is still",
        pose=pose,
        axis=axes[0] if len(axes) == 1 else None,
    )


def calibration_failed(exc: CalibrationError) -> FailureReason:
    """The poses gave no trustworthy calibration (``exc`` says why, and which pose)."""
    pose_note = f" (pose {exc.pose + 1})" if exc.pose is not None else ""
    return FailureReason(code="calibration", message=f"{exc}{pose_note}", pose=exc.pose)


def writeback_failed(exc: Exception) -> FailureReason:
    """The unit did not take its coefficients (``exc``: the device's error)."""
    return FailureReason(code="writeback", message=f"write-back failed: {exc}")


def gyro_matrix_failed(exc: Exception) -> FailureReason:
    """The moves between the poses could not give the gyro matrix (``exc`` says why,
    move by move: cut short past :data:`MESSAGE_MAX` characters)."""
    message = f"gyro matrix: {exc}"
    if len(message) > MESSAGE_MAX:
        message = message[: MESSAGE_MAX - 1] + "…"
    return FailureReason(code="gyro_matrix", message=message)


def verification_move_failed(problem: str) -> FailureReason:
    """The verification move gave no angle to check the unit's own gyros with."""
    return FailureReason(code="gyro_verification", message=f"verification move: {problem}")


class Failures:
    """The failures of one run found while it goes."""

    def __init__(self) -> None:
        self.found: list[FailureReason] = []

    def add(self, reason: FailureReason) -> None:
        """A failure found while the run goes."""
        self.found.append(reason)

    def abort(self, *, written: bool) -> None:
        """The operator stopped the run: the abort replaces whatever was found."""
        if written:  # the unit holds them: not an abort that left it as it was
            self.found = [
                FailureReason(
                    code="unit_output",
                    message="aborted by the operator after the coefficients were written: "
                    "the unit's own output was not checked",
                )
            ]
        else:
            self.found = [FailureReason(code="aborted", message="aborted by the operator")]

    @property
    def aborted(self) -> bool:
        """Whether the operator aborted the run before the write-back."""
        return any(f.code == "aborted" for f in self.found)


@dataclass(frozen=True)
class Judged:
    """A run's verdict and its failures: what its disposition is decided on."""

    verdict: Verdict
    failures: tuple[FailureReason, ...]


@dataclass(frozen=True)
class Purpose:
    """What the run is for, which decides where its unit goes: a production unit with its
    ``earlier`` runs and the profile's retest limit, or the station's golden unit."""

    earlier: Sequence[Run] = ()
    golden: bool = False

    def disposition(self, judged: Judged, attempts_allowed: int) -> Disposition | None:
        """Where the unit goes (None: the golden unit goes back to its place)."""
        if self.golden:
            return None
        return disposition(judged, self.earlier, attempts_allowed)


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
    purpose: Purpose,
    evidence: PoseRecord | None = None,
    gyro_checks: Sequence[FailureReason] = (),
    gyro_matrix: GyroMatrixRecord | None = None,
    gyro_fit: GyroMatrixFit | None = None,
    store: bool,
) -> Conclusion:
    """The verdict of the run and, if ``store``, its record.

    ``evidence`` is the live window that failed the unit before its pose was captured;
    ``gyro_checks`` the limit checks of a whole-unit run's gyro matrix (found while it
    went), ``gyro_matrix`` that matrix as recorded and ``gyro_fit`` its fit (for its
    uncertainty).
    """
    captures = journal.captures
    fit_count = len(settings.poses)
    gyro = record.gyro_summary(captures, fit_count, solution)
    for reason in gyro_checks:
        failures.add(reason)
    error = _verification_error_mg(captures, solution, fit_count)
    uncertainty = record.uncertainty_record(
        captures, fit_count, solution, gyro_fit, settings.sensor
    )
    measured = _measured(captures, solution, fit_count, error, gyro, gyro_matrix, uncertainty)
    if failures.aborted:
        reasons, error = list(failures.found), None
    else:
        reasons = verdict_failures(failures.found, limit_checks(profile, measured))
    if not store:
        return Conclusion(error, None)
    judged = Judged("fail" if reasons else "pass", tuple(reasons))
    run = record.run_record(
        journal,
        settings,
        profile,
        solution,
        verdict=judged.verdict,
        failures=judged.failures,
        disposition=purpose.disposition(judged, profile.attempts_allowed),
        golden=purpose.golden,
        verification_error_mg=error,
        gyro=gyro,
        poses=record.pose_records(captures, evidence),
        gyro_matrix=gyro_matrix,
        uncertainty=uncertainty,
        check_rules=check_rules(profile, measured),
    )
    return Conclusion(error, run)


def _verification_error_mg(
    captures: Mapping[int, Capture], solution: Solution | None, fit_count: int
) -> float | None:
    """How far the verification pose's calibrated |g| is from 1 g (mg), once taken."""
    if solution is None or fit_count not in captures:
        return None
    raw = np.array(captures[fit_count].record.mean.as_tuple())
    return abs(float(np.linalg.norm(apply(solution.calibration, raw))) - 1.0) * 1000.0


def _measured(
    captures: Mapping[int, Capture],
    solution: Solution | None,
    fit_count: int,
    verification_error_mg: float | None,
    gyro: GyroSummary | None,
    gyro_matrix: GyroMatrixRecord | None,
    uncertainty: UncertaintyRecord | None = None,
) -> Measured:
    """What the limits judge, from the poses taken, the solve, the gyro summary, the gyro
    matrix K and the uncertainties of the coefficients, K and the verification error."""
    calibration = solution.calibration if solution is not None else None
    u = uncertainty
    return Measured(
        pose_noise={i: c.record.std.as_tuple() for i, c in captures.items()},
        link_loss={i: c.loss_fraction for i, c in captures.items()},
        offset=None if calibration is None else _triple(calibration.offset),
        sensitivity=None if calibration is None else _triple(calibration.sensitivity),
        verification=None if verification_error_mg is None else (fit_count, verification_error_mg),
        gyro_bias=None if gyro is None else gyro.bias.as_tuple(),
        gyro_matrix=None if gyro_matrix is None else gyro_matrix.matrix,
        uncertainty=uncertainty_of(
            None if u is None or u.offset is None else u.offset.as_tuple(),
            None if u is None or u.sensitivity is None else u.sensitivity.as_tuple(),
            None if u is None or u.gyro_bias_dps is None else u.gyro_bias_dps,
            None if u is None or verification_error_mg is None else u.verification_error_mg,
            None if u is None or gyro_matrix is None else u.gyro_matrix,
        ),
    )


def _triple(values: np.ndarray) -> tuple[float, float, float]:
    return (float(values[0]), float(values[1]), float(values[2]))
