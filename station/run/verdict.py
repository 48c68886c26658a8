"""The failures found during a run, and the list its verdict is made of.

Failures found while the run goes (a saturated axis, a failed solve or write-back, the
unit's output) are kept in the order found; at the end the limit checks of
:mod:`station.run.checks` are added, unless the operator aborted (an abort says nothing
about the unit). An abort after the write-back is not recorded as an abort: the unit
holds the coefficients, and its own output was not checked.
"""

from collections.abc import Mapping

from station.domain.calibration import CalibrationError, Solution
from station.domain.judging import verdict_failures
from station.domain.limits import LimitsProfile
from station.domain.records import FailureReason, GyroSummary
from station.results.journal import Capture
from station.run.checks import CheckResult, run_checks


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


#: Longest failure message kept (the record's limit is 500 characters).
MESSAGE_MAX = 300


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
    """The failures of one run so far."""

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

    def final(
        self,
        profile: LimitsProfile,
        captures: Mapping[int, Capture],
        solution: Solution | None,
        fit_count: int,
        gyro: GyroSummary | None,
    ) -> CheckResult:
        """The verdict's failures: those found, then the limit checks not among them.

        With the verification pose's error (mg) when it was checked; an abort is not
        checked.
        """
        if self.aborted:
            return CheckResult(list(self.found), None)
        calibration = solution.calibration if solution is not None else None
        checked = run_checks(profile, captures, calibration, fit_count, gyro)
        reasons = verdict_failures(self.found, checked.reasons)
        return CheckResult(reasons, checked.verification_error_mg)
