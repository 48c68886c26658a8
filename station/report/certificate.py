"""What a calibration certificate (or a failed unit's failure report) states about its run.

The content ISO/IEC 17025:2017 clause 7.8 asks of a calibration certificate (7.8.2: a
unique identification, the item's identity, the date, the method, the results with their
units, the person who authorised it; 7.8.4: the measurement uncertainty, the conditions,
the traceability; 7.8.6: the decision rule of a statement of conformity), from the stored
run alone: :func:`identity` is the block both documents open with, one place for both.
The page (``templates/certificate.html`` and its ``identity.html``) lays it out.
"""

import math
from dataclasses import dataclass
from datetime import datetime

import numpy as np

from station.domain.calibration.uncertainty import DISTURBED_SPREAD_RATIO, disturbed_poses
from station.domain.i18n import ENGLISH, Say
from station.domain.product.laboratory import Laboratory
from station.domain.product.limits import CHECKS, Bounds, LimitsProfile
from station.domain.record.records import PoseRecord, RunRecord, RunSummary, StoredCoefficients
from station.report.explanations import check_name, unit_words
from station.report.formatting import number

#: The document's number prefix by the run's verdict: a certificate, or a failure report.
NUMBER_PREFIXES = {"pass": "CAL", "fail": "FR"}

#: Hex digits of the run id in a document's number: 48 random bits of a version-4 UUID,
#: so that a line's runs of a year share a number with odds below 1 in 500 at a million
#: runs (n²/2⁴⁹); 8 digits (32 bits) would collide about once in 100,000 runs.
NUMBER_DIGITS = 12


def document_number(run: RunRecord | RunSummary) -> str:
    """The document's number: ``CAL-<year>-<run id>`` for a certificate, ``FR-…`` for a
    failure report; the year the run started (UTC) and the first :data:`NUMBER_DIGITS` hex
    digits of its run id. Derived from the stored run only, so the same run always gets
    the same number, whoever prints it when (ISO/IEC 17025 7.8.2.1 b: a unique
    identification)."""
    prefix = NUMBER_PREFIXES[run.verdict]
    return f"{prefix}-{run.started_at.year:04d}-{run.run_id.hex[:NUMBER_DIGITS].upper()}"


def mean_temperature(run: RunRecord) -> float | None:
    """The mean of the run's pose temperatures, °C (ISO/IEC 17025 7.8.4.1 a: the
    conditions); None when no pose recorded one."""
    values = [p.temperature_c for p in run.poses if p.temperature_c is not None]
    return math.fsum(values) / len(values) if values else None


def temperature_range(run: RunRecord) -> tuple[float, float] | None:
    """The lowest and highest pose temperature of the run, °C: the range the results
    hold in (ISO/IEC 17025 7.8.4.1 a: the conditions that influence the results; the
    coefficients drift with temperature, ``docs/calibration.md``); None when no pose
    recorded one."""
    values = [p.temperature_c for p in run.poses if p.temperature_c is not None]
    return (min(values), max(values)) if values else None


@dataclass(frozen=True)
class CoefficientState:
    """One set of coefficients of the unit, as found or as left (ISO/IEC 17025:2017
    7.8.4.1: the results before and after adjustment): offset (counts) and the
    counts-to-g matrix (g/count), ``g = matrix @ (raw − offset)``; ``sensitivity`` per
    axis, 1 / the matrix's diagonal (counts/g); ``error_mg``: the largest ||g| − 1| these
    coefficients make of the run's fit poses, mg (the unit's own output on them);
    ``written``: False while the unit held its factory defaults."""

    written: bool
    offset: tuple[float, float, float]
    matrix: tuple[tuple[float, ...], ...]
    sensitivity: tuple[float, float, float]
    error_mg: float


@dataclass(frozen=True)
class GyroState:
    """The gyro coefficients as found or as left: bias (deg/s) and K⁻¹, ``rate = K⁻¹ ·
    (measured − bias)`` (``docs/protocol.md``)."""

    written: bool
    bias_dps: tuple[float, float, float]
    inverse: tuple[tuple[float, ...], ...]


def _state(
    run: RunRecord, offset: tuple[float, ...], matrix: tuple[tuple[float, ...], ...], written: bool
) -> CoefficientState:
    """The coefficients ``offset``, ``matrix`` judged on ``run``'s fit poses."""
    m, o = np.array(matrix, dtype=float), np.array(offset, dtype=float)
    raw = np.array([p.mean.as_tuple() for p in run.poses if p.role == "fit"], dtype=float)
    with np.errstate(all="ignore"):
        error = np.abs(np.linalg.norm((raw - o) @ m.T, axis=1) - 1.0) * 1000.0
        diagonal = [1.0 / v if v else math.inf for v in np.diag(m).tolist()]
    return CoefficientState(
        written=written,
        offset=(o[0].item(), o[1].item(), o[2].item()),
        matrix=matrix,
        sensitivity=(diagonal[0], diagonal[1], diagonal[2]),
        error_mg=float(np.max(error)) if error.size else math.nan,
    )


def as_found(run: RunRecord) -> CoefficientState | None:
    """The accelerometer coefficients the unit held when it came; None when the run's
    record does not hold them (runs from before the station read them)."""
    found = run.as_found
    if found is None:
        return None
    held = found.accelerometer
    return _state(run, held.offset, held.matrix, held.written)


def as_left(run: RunRecord) -> CoefficientState | None:
    """The accelerometer coefficients a passing run wrote and read back (its write-back
    verified within the ``writeback`` limit); None for a run that did not pass (whether
    its coefficients reached the unit is not stated)."""
    cal = run.coefficients
    if cal is None or run.verdict != "pass":
        return None
    return _state(run, cal.offset.as_tuple(), cal.matrix, True)


def _gyro_state(held: StoredCoefficients) -> GyroState:
    return GyroState(written=held.written, bias_dps=held.offset, inverse=held.matrix)


def gyro_as_found(run: RunRecord) -> GyroState | None:
    """The gyro coefficients the unit held when it came (whole-unit runs), else None."""
    found = run.as_found
    return None if found is None or found.gyro is None else _gyro_state(found.gyro)


def gyro_as_left(run: RunRecord) -> GyroState | None:
    """The gyro coefficients a passing run wrote: the bias and K⁻¹ of its gyro matrix."""
    k = run.gyro_matrix
    if k is None or run.verdict != "pass":
        return None
    inverse = np.linalg.inv(np.array(k.matrix, dtype=float))
    return GyroState(
        written=True,
        bias_dps=k.bias_dps.as_tuple(),
        inverse=tuple(tuple(row) for row in inverse.tolist()),
    )


def method(run: RunRecord, tr: Say = ENGLISH) -> list[tuple[str, str]]:
    """The methods that produced the run's results, each with its source, in the
    reader's language (``tr``: :func:`station.domain.i18n.speaker`)."""
    rule = run.decision_rule or "simple"
    lines = [
        (
            tr("accelerometer"),
            tr(
                "six-position autocalibration: offset and sensitivity per axis from |g| = 1 "
                "[Song2006]"
            )
            if run.model == "six"
            else tr(
                "six-position autocalibration [Song2006] with the nine-parameter model "
                "(offset, sensitivity, axis misalignment) fitted by least squares [Tedaldi2014]"
            ),
        ),
    ]
    if run.gyro is not None:
        lines.append((tr("gyro bias"), tr("mean rate of the still poses")))
    if run.gyro_matrix is not None:
        lines.append(
            (tr("gyro matrix K"), tr("fitted from the moves between still poses [Tedaldi2014]"))
        )
    lines.append(
        (
            tr("uncertainty"),
            tr(
                "expanded uncertainty U = k·u_c, k = 2, evaluated per JCGM 100:2008 (GUM), "
                "validated by Monte Carlo per JCGM 101:2008"
            ),
        )
    )
    lines.append(
        (
            tr("decision rule"),
            tr("simple acceptance: a value within its limits conforms (ILAC-G8:09/2019 §4.2.1)")
            if rule == "simple"
            else tr(
                "guarded acceptance, guard band w = U: a value conforms when value ± U lies "
                "within its limits (ILAC-G8:09/2019 §4.2.2, JCGM 106:2012)"
            ),
        )
    )
    return lines


@dataclass(frozen=True)
class CheckRow:
    """One check of the run against its limits: what, in which unit, the bounds, the
    measured values (``"x 2048.1, y …"``; empty when the run did not reach it), its
    result (``pass``, ``fail`` or ``not reached``) and the decision rule that judged it
    with its guard band (``"guarded acceptance, w = U: x 0.1, …"``, in the reader's
    language)."""

    name: str
    unit: str
    lower: float | None
    upper: float | None
    measured: str
    result: str
    rule: str = ""


def _triple(values: tuple[float, float, float]) -> str:
    return ", ".join(f"{axis} {value:.6g}" for axis, value in zip("xyz", values, strict=True))


def _measured(run: RunRecord, code: str, tr: Say) -> str:
    """What the run measured for check ``code``, as the check judged it; "" if nothing."""
    cal, matrix = run.coefficients, run.gyro_matrix
    if code == "offset" and cal is not None:
        return _triple(cal.offset.as_tuple())
    if code == "sensitivity" and cal is not None:
        return _triple(cal.sensitivity.as_tuple())
    if code == "verification_error" and run.quality is not None:
        value = run.quality.verification_error_mg
        return "" if value is None else f"{value:.6g}"
    if code == "pose_noise":
        return tr("largest {value}", value=f"{max(max(p.std.as_tuple()) for p in run.poses):.6g}")
    if code == "gyro_bias" and run.gyro is not None:
        return _triple(run.gyro.bias.as_tuple())
    if code == "gyro_scale" and matrix is not None:
        k = matrix.matrix
        return _triple((k[0][0] - 1, k[1][1] - 1, k[2][2] - 1))
    if code == "gyro_misalignment" and matrix is not None:
        off = [abs(matrix.matrix[i][j]) for i in range(3) for j in range(3) if i != j]
        return tr("largest {value}", value=f"|K_ij| {max(off):.6g}")
    if code == "gyro_verification" and matrix is not None and matrix.verification_deg is not None:
        return f"{matrix.verification_deg:.6g}"
    return ""


def _guard_band(run: RunRecord, code: str) -> str:
    """The U a guarded rule used as the guard band of check ``code`` ("" if none)."""
    u = run.uncertainty
    if u is None:
        return ""
    k = u.gyro_matrix
    values = {
        "offset": None if u.offset is None else u.offset.as_tuple(),
        "sensitivity": None if u.sensitivity is None else u.sensitivity.as_tuple(),
        "gyro_bias": u.gyro_bias_dps,
        "gyro_scale": None if k is None else (k[0][0], k[1][1], k[2][2]),
    }.get(code)
    if values is not None:
        return _triple((values[0], values[1], values[2]))
    if code == "verification_error" and u.verification_error_mg is not None:
        return f"{u.verification_error_mg:.3g}"
    if code == "gyro_misalignment" and k is not None:
        return f"≤ {max(k[i][j] for i in range(3) for j in range(3) if i != j):.3g}"
    return ""


def _rule_words(run: RunRecord, code: str, tr: Say) -> str:
    """The decision rule that judged check ``code`` and its guard band, as the document
    says it (:meth:`~station.domain.record.records.RunRecord.rule_of`)."""
    if run.rule_of(code) == "simple":
        return tr("simple acceptance")
    return tr("guarded acceptance, w = U: {u}", u=_guard_band(run, code) or "—")


def _quantities(tr: Say) -> dict[str, str]:
    """Each check's quantity after its name on the page, where the name alone does not
    say which (:func:`check_rows`)."""
    return {"pose_noise": tr("(std)"), "gyro_scale": "K_ii − 1", "gyro_misalignment": "K_ij"}


def check_rows(run: RunRecord, profile: LimitsProfile, tr: Say = ENGLISH) -> list[CheckRow]:
    """Every check ``profile`` bounds, with its unit, its bounds, what the run measured
    and its result (ISO/IEC 17025 7.8.6: the statement of conformity of each
    quantity): ``fail`` when the run failed it, ``pass`` when the run passed or
    measured it without failing it, else ``not reached`` (the run stopped before): a
    code. Names, units and what was measured in the reader's language (``tr``)."""
    failed = {f.code for f in run.failures}
    rows = []
    for code, field in CHECKS.items():
        bounds: Bounds | None = getattr(profile, field)
        if bounds is None:
            continue
        measured = _measured(run, code, tr)
        result = (
            "fail"
            if code in failed
            else "pass"
            if run.verdict == "pass" or measured
            else "not reached"
        )
        rows.append(
            CheckRow(
                name=" ".join(filter(None, (check_name(code, tr), _quantities(tr).get(code)))),
                unit=unit_words(code, tr) or tr("fraction"),
                lower=bounds.lower,
                upper=bounds.upper,
                measured=measured,
                result=result,
                rule=_rule_words(run, code, tr),
            )
        )
    return rows


def _terms(run: RunRecord, tr: Say) -> list[str]:
    """What the expanded uncertainty U of the coefficients holds, the budget's terms in
    its order (:data:`station.domain.calibration.uncertainty.TERMS`; the fixture's tilt is
    zero by construction)."""
    terms = [tr("pose noise"), tr("ADC quantisation")]
    if run.model == "six":
        terms.append(tr("the six-parameter model's unmodelled cross-axis coupling"))
    terms.append(tr("the fit's evidence"))
    u = run.uncertainty
    if u is None or "temperature" not in (u.excluded_influences or ()):
        terms.append(tr("the sensor's drift with temperature across the poses"))
    return terms


def influences(run: RunRecord, tr: Say = ENGLISH) -> list[tuple[str, str]]:
    """Every influence on the results, as the certificate states it (ISO/IEC 17025:2017
    7.8.4.1: the conditions that influence the results, the measurement uncertainty):
    what U holds; each influence the record names as left out of U, and why
    (``uncertainty.excluded_influences``); each fitted pose de-weighted because it was
    disturbed while taken (its spread more than
    :data:`~station.domain.calibration.uncertainty.DISTURBED_SPREAD_RATIO` times the
    sensor's noise, from the poses' spreads as the budget found them,
    :func:`~station.domain.calibration.uncertainty.disturbed_poses`); the temperature
    range the results hold in; and the decision rule with its guard band. Rows of (what,
    statement) in the reader's language (``tr``); none when the run recorded no U."""
    u = run.uncertainty
    if u is None:
        return []
    rows = [(tr("in U"), ", ".join(_terms(run, tr)))]
    why = {
        "temperature": tr(
            "not in U: no temperature was recorded at the poses, so the sensor's drift "
            "across them is not in U"
        ),
        "gyro_bias_repeatability": tr(
            "not in U: the product's gyros declare no turn-on to turn-on repeatability of "
            "their bias, so U holds this session's mean only"
        ),
    }
    names = {
        "temperature": tr("temperature"),
        "gyro_bias_repeatability": tr("gyro bias repeatability"),
    }
    for influence in u.excluded_influences or ():
        rows.append((names[influence], why[influence]))
    for pose, ratio in disturbed(run):
        rows.append(
            (
                tr("disturbed pose {pose} ({name})", pose=pose.index + 1, name=pose.name),
                tr(
                    "its spread was {ratio} times the sensor's noise (above {limit}): "
                    "de-weighted, its excess variance in U undivided by its samples",
                    ratio=number(ratio, 3),
                    limit=number(DISTURBED_SPREAD_RATIO, 2),
                ),
            )
        )
    span = temperature_range(run)
    rows.append(
        (
            tr("temperature range"),
            tr(
                "the results hold at {low} … {high} °C (the run's poses); elsewhere add the "
                "sensor's drift with temperature to U",
                low=number(span[0], 4),
                high=number(span[1], 4),
            )
            if span is not None
            else tr("not recorded: the results hold at the temperature of the calibration"),
        )
    )
    rule = run.decision_rule or "simple"
    rows.append(
        (
            tr("decision rule"),
            tr("simple acceptance: a value within its limits conforms, whatever its U")
            if rule == "simple"
            else tr(
                "guarded acceptance with guard band w = U: a value that carries its U "
                "conforms when value ± U lies within its limits; each limit's rule and U "
                "are under Limits"
            ),
        )
    )
    return rows


def disturbed(run: RunRecord) -> list[tuple[PoseRecord, float]]:
    """The fitted poses of ``run`` de-weighted because disturbed while taken, each with
    its largest spread over the sensor's noise (the poses the budget left out as
    inconsistent are not fitted)."""
    fit = run.fit_poses()
    if not fit:
        return []
    left_out = set(run.quality.excluded_poses or ()) if run.quality is not None else set()
    kept = [i for i, pose in enumerate(fit) if pose.index not in left_out]
    spread = np.array([pose.std.as_tuple() for pose in fit], dtype=float)
    _, found = disturbed_poses(spread, kept)
    return [(fit[i], ratio) for i, ratio in sorted(found.items())]


@dataclass(frozen=True)
class Identity:
    """The identity block a certificate and a failure report share: the document's
    number, the laboratory (configured), the item, its receipt and condition, the
    conditions, the method, the reference and its traceability, the dates."""

    number: str
    laboratory: Laboratory
    temperature_c: float | None
    #: The poses' lowest and highest temperature, °C; None: not recorded.
    temperature_range: tuple[float, float] | None
    method: list[tuple[str, str]]
    #: That shift's golden-unit check at the run's station (the reference); None: none.
    golden: RunSummary | None
    #: When the station received the unit and read what it held; None: not recorded.
    received_at: datetime | None
    #: The item's condition on receipt, in the reader's language; None: not recorded.
    condition: str | None
    issued_at: datetime


def condition(run: RunRecord, tr: Say = ENGLISH) -> str | None:
    """The item's condition when the station received it (ISO/IEC 17025:2017 7.8.2.1 g,
    7.8.4.1): it answered with its serial number and held its factory defaults or
    coefficients written before; None when the record does not hold what it held."""
    found = run.as_found
    if found is None:
        return None
    if found.accelerometer.written:
        return tr("answered as its serial; held coefficients written before (as found, below)")
    return tr("answered as its serial; held its factory defaults (never calibrated)")


def identity(
    run: RunRecord,
    golden: RunSummary | None,
    tr: Say = ENGLISH,
    *,
    laboratory: Laboratory | None = None,
    issued_at: datetime,
) -> Identity:
    """The identity block of ``run``'s document; ``golden``: the latest golden-unit run
    of its station in its shift before it (``db.RunRepository.latest_golden``); the
    configured ``laboratory`` (none: every field "not configured"); its method and the
    item's condition in the reader's language (``tr``); ``issued_at``: the date of issue."""
    return Identity(
        number=document_number(run),
        laboratory=laboratory or Laboratory(),
        temperature_c=mean_temperature(run),
        temperature_range=temperature_range(run),
        method=method(run, tr),
        golden=golden,
        received_at=run.as_found.read_at if run.as_found is not None else None,
        condition=condition(run, tr),
        issued_at=issued_at,
    )


def failure_words(tr: Say) -> dict[str, str]:
    """The words of the document's title and of its failures (the failure report's "what
    failed"), in the reader's language (``tr``: :func:`station.domain.i18n.speaker`)."""
    return {
        "pass": tr("Calibration certificate"),
        "fail": tr("Failure report"),
        "on_hold": tr("the unit's latest run failed: it is on hold, not certified"),
        "what_failed": tr("What failed"),
        "code": tr("code"),
        "explanation": tr("explanation"),
        "measured": tr("measured"),
        "lower": tr("lower"),
        "upper": tr("upper"),
        "none": tr("none"),
        "failure_reasons": tr("failure reasons"),
    }


def code_words(tr: Say) -> dict[str, str]:
    """The stored codes the documents show as words, in the reader's language: verdicts,
    a check's result, a pose's role, a review's decision, a decision rule."""
    return {
        "pass": tr("pass"),
        "fail": tr("fail"),
        "not reached": tr("not reached"),
        "fit": tr("fit"),
        "verify": tr("verify"),
        "retest": tr("retest"),
        "scrap": tr("scrap"),
        "simple": tr("simple acceptance"),
        "guarded": tr("guarded acceptance"),
    }
