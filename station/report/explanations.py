"""A failure's explanation in the operator's language, from what the run stores.

A run records each failure reason (:class:`station.domain.record.records.FailureReason`) with its
code, the station's English sentence and the parameters the sentence was made of: the
value measured, the bounds, the axis and the pose. The sentence is the record and stays
as it was said; English renders it as it is. Korean and Chinese render the reason from
its code and parameters through the catalogues (:mod:`station.domain.i18n`): a limit
check (:func:`station.domain.product.limits.check`) names the check, its axis and pose, the value
with its unit and the bounds it missed; the failures found while the run went (a
saturated axis, no calibration, a failed write-back, no gyro matrix, no verification
move, an abort) say what happened, with the pose when it is known (the device's or the
solver's own English detail stays in the record). Codes, serials and numbers are not
translated.
"""

from station.domain.i18n import Say, language, speaker
from station.domain.product.limits import UNITS, Bounds
from station.domain.record.records import FailureReason


def explanation(failure: FailureReason, lang: str | None = None) -> str:
    """``failure`` explained in ``lang`` (default: the operator's language)."""
    lang = lang or language()
    if lang == "en":
        return failure.message or failure.code
    tr = speaker(lang)
    if failure.lower is not None or failure.upper is not None:
        return _limit_check(failure, tr)
    said, where = _found(failure.code, failure.axis, tr), _where(failure, tr)
    return f"{said} {where}" if where else said


def _where(failure: FailureReason, tr: Say) -> str:
    """The pose the failure names, if any: ``(pose 3)``."""
    return "" if failure.pose is None else tr("(pose {number})", number=failure.pose + 1)


def _limit_check(failure: FailureReason, tr: Say) -> str:
    """A value outside its bounds, or inside them by less than its uncertainty U when the
    profile's rule is guarded acceptance (ILAC-G8:09/2019 §4.2.2)."""
    subject = " ".join(
        part
        for part in (check_name(failure.code, tr), failure.axis or "", _where(failure, tr))
        if part
    )
    bounds = Bounds(lower=failure.lower, upper=failure.upper)
    limits = bounds.describe()
    if failure.measured is None:
        return tr("{subject}: no finite value, limits {limits}", subject=subject, limits=limits)
    unit = unit_words(failure.code, tr)
    value = f"{failure.measured:.6g}" + (f" {unit}" if unit else "")
    if bounds.contains(failure.measured):
        if failure.uncertainty is None:  # stored before U was (revision 0016)
            return tr(
                "{subject} {value} within {limits} but nearer a limit than its uncertainty U "
                "(guarded acceptance, w = U)",
                subject=subject,
                value=value,
                limits=limits,
            )
        u = f"{failure.uncertainty:.3g}" + (f" {unit}" if unit else "")
        return tr(
            "{subject} {value} within {limits} but nearer a limit than its uncertainty "
            "U = {u} (guarded acceptance, w = U)",
            subject=subject,
            value=value,
            limits=limits,
            u=u,
        )
    return tr("{subject} {value} outside {limits}", subject=subject, value=value, limits=limits)


def check_name(code: str, tr: Say) -> str:
    """A limit check's name (:data:`station.domain.product.limits.CHECKS`); its code if unknown."""
    names = {
        "offset": tr("offset"),
        "sensitivity": tr("sensitivity"),
        "verification_error": tr("verification pose error"),
        "pose_noise": tr("pose noise"),
        "gyro_bias": tr("gyro bias"),
        "link_loss": tr("link loss"),
        "writeback": tr("write-back relative error"),
        "unit_output": tr("unit's own output after write-back"),
        "gyro_scale": tr("gyro scale error"),
        "gyro_misalignment": tr("gyro misalignment"),
        "gyro_verification": tr("gyro verification move"),
    }
    return names.get(code, code)


def unit_words(code: str, tr: Say) -> str:
    """A check's unit (:data:`station.domain.product.limits.UNITS`) as the operator reads it."""
    units = {
        "counts": tr("counts"),
        "counts/g": tr("counts/g"),
        "deg/s": tr("deg/s"),
        "deg": tr("deg"),
    }
    unit = UNITS.get(code, "")
    return units.get(unit, unit)


def _found(code: str, axis: str | None, tr: Say) -> str:
    """A failure found while the run went (:mod:`station.run.verdict`), by its code."""
    if code == "saturated":
        if axis is not None:
            return tr(
                "accelerometer {axis} stuck at the ADC rail while the unit is still", axis=axis
            )
        return tr("accelerometer stuck at the ADC rail while the unit is still")
    said = {
        "calibration": tr("the poses gave no trustworthy calibration"),
        "writeback": tr("write-back failed: the unit did not take its coefficients"),
        "gyro_matrix": tr("the moves between the poses gave no gyro matrix"),
        "gyro_verification": tr("the verification move gave no angle to check the gyros with"),
        "unit_output": tr(
            "aborted by the operator after the coefficients were written: "
            "the unit's own output was not checked"
        ),
        "aborted": tr("aborted by the operator"),
    }
    return said.get(code) or tr("check {code} failed", code=code)
