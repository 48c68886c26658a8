"""A fit that cannot be fooled: the residual limit, and one bad pose found and left out.

With N poses and p unknowns (6 or 9) a least-squares fit has N − p spare equations, and
only they can show a bad pose ([Song2006]_: six poses fit exactly and show nothing).
Every fitted pose's **studentised residual** t_i = r_i/√(1 − h_i) (counts along gravity,
h_i the pose's leverage; :mod:`station.domain.calibration.solution`) is compared with a limit L:

* max |t_i| ≤ L: the poses are consistent; nothing is left out.
* N − p ≥ 2 (eight poses for the six-parameter model, eleven for nine): every pose is
  left out in turn and the fit redone; when exactly one such refit is consistent and
  every other pose is cleared (its refit made and inconsistent, or failed on a sound
  geometry: the rest still hold the bad pose), that pose is excluded and named. When two
  are (the spare equations cannot tell them apart), or none is (more than one bad pose),
  or a pose's leaving out leaves a geometry too narrow to fit (that pose cannot be
  cleared, and a good pose's refit may absorb it and look consistent: simulated
  cap-shaped sets of 8–10 poses were calibrated wrong so, 43 of 6,000, when only the
  three largest |t_i| were tried), the set is refused, naming what the evidence allows.
  For one bad pose k its |t_k| is the largest of all to first order (Cauchy–Schwarz on
  the columns of I − H), but a large error moves the fit far from that picture.
* A pose far enough off can stop the fit over all poses from finding an ellipsoid, or
  land it on a degenerate one, though the poses' geometry is sound: then no residuals
  rank the candidates, and with N − p ≥ 2 every pose is left out in turn, judged as
  above: a pose whose leaving out cannot be fitted for the rest's geometry (coplanar,
  say) cannot be cleared, and a good pose's refit may then absorb the bad one and look
  consistent (simulated cap-shaped sets of 8–10 poses found sensitivities of 183–335
  counts/g so). Then, and on a degenerate geometry, the fit's own refusal stands.
* N − p = 1 (seven poses, six-parameter model): the residuals all lie along one vector,
  every pose's |t_i| is the same, and leaving out any one pose fits the other six exactly.
  The evidence cannot name the pose, so the set is refused without blaming one (the largest
  raw residual would often blame the wrong pose).

The limit L comes from the limits profile (``fit_residual_counts``) or, by default, from
the noise (:func:`residual_limit`, in the sensor's counts; the putter's is
:data:`DEFAULT_RESIDUAL_LIMIT_COUNTS`): a pose mean's noise σ is at most the sample
spread the stillness check lets through, 8 counts of the putter (twice its limit,
:func:`station.domain.signals.stillness.spread_limit_counts`), over the 1024 samples of a pose,
σ = 0.25 counts; L = 8σ = 2 counts gives a false alarm on a clean pose with probability
2·(1 − Φ(8)) ≈ 1e-15 at that worst noise (fewer at the sensor's real ~1 count). The
six-parameter model cannot represent the KXM52's ~2 % cross-axis coupling, which alone
leaves up to 2·0.02·860 ≈ 34 counts (largest of 300 simulated units with 8–18 poses:
35), so its default is 40 counts: it catches gross errors only, the nine-parameter model
catches 2-count ones.
"""

import math
from contextlib import suppress
from dataclasses import replace

import numpy as np

from station.domain.arrays import FloatArray
from station.domain.calibration.errors import (
    CalibrationError,
    CoplanarPosesError,
    DuplicatePoseError,
    IllConditionedError,
    InconsistentPosesError,
    NonPositiveScaleError,
    TooFewPosesError,
)
from station.domain.calibration.geometry import GeometryLimits, refuse_beyond_datasheet
from station.domain.calibration.least_squares import (
    UNKNOWNS,
    refuse_degenerate_geometry,
    solve_least_squares,
)
from station.domain.calibration.model import Model, apply
from station.domain.calibration.residual import MAX_CONDITION, normalise
from station.domain.calibration.solution import Solution
from station.domain.sensors.sensor import SAMPLES_PER_POSE
from station.domain.sensors.sensor_spec import PUTTER_SENSOR, SensorSpec
from station.domain.signals.stillness import spread_limit_counts

#: The largest sample spread a still pose may have, in the stillness limit's spreads:
#: twice it (8 counts of the putter).
POSE_SPREAD_LIMITS = 2.0
#: The noise limit in σ of a pose mean: 2·(1 − Φ(8)) ≈ 1.2e-15 false alarms per pose.
NOISE_SIGMAS = 8.0


def pose_mean_noise_counts(sensor: SensorSpec = PUTTER_SENSOR) -> float:
    """A pose mean's noise at the largest sample spread a still pose of ``sensor`` may
    have, counts (the putter: 8 counts over 1024 samples, 0.25 counts)."""
    return POSE_SPREAD_LIMITS * spread_limit_counts(sensor) / math.sqrt(SAMPLES_PER_POSE)


#: Default limit on |studentised residual| of the putter, counts: 8σ of a pose mean, 2 counts.
DEFAULT_RESIDUAL_LIMIT_COUNTS = NOISE_SIGMAS * pose_mean_noise_counts()
#: Spare equations needed to find and leave out one pose (N ≥ p + 2).
EXCLUSION_MIN_SPARE = 2


def residual_limit(configured: float | None, sensor: SensorSpec = PUTTER_SENSOR) -> float:
    """The limit on |studentised residual| in ``sensor``'s counts: ``configured`` or the
    default, 8σ of a pose mean."""
    return NOISE_SIGMAS * pose_mean_noise_counts(sensor) if configured is None else configured


def check_model(model: Model, poses: int) -> Model:
    """The model the poses are judged with: the nine-parameter one whenever there are
    poses enough for it to find a bad pose, as it leaves only noise on a coupled unit."""
    return "nine" if poses >= UNKNOWNS["nine"] + EXCLUSION_MIN_SPARE else model


def solve_consistent(
    poses: FloatArray,
    model: Model,
    limits: GeometryLimits = GeometryLimits(),
    max_condition: float = MAX_CONDITION,
    max_residual_counts: float | None = None,
) -> Solution:
    """Least squares over N poses (N, 3) that leaves out one inconsistent pose or refuses.

    Raises:
        InconsistentPosesError: the residuals exceed the limit and leaving out one pose
            does not explain it, or too few poses to say which.
        CalibrationError: any refusal of :func:`solve_least_squares`.
    """
    limit = residual_limit(max_residual_counts, limits.sensor)
    try:
        fit = solve_least_squares(poses, model, limits, max_condition)
    except (IllConditionedError, NonPositiveScaleError) as failed:
        judge = check_model(model, len(poses))
        if len(poses) - UNKNOWNS[judge] < EXCLUSION_MIN_SPARE:
            raise
        refuse_degenerate_geometry(normalise(poses), model, max_condition)
        head = f"poses inconsistent: the fit over all poses failed ({failed})"
        try:
            found = _explained(poses, model, judge, limits, max_condition, limit, head)
        except _UnclearedPoseError:
            raise failed from None
        if found is not None:
            return found
        raise
    judge, judged = model, fit
    if (wider := check_model(model, len(poses))) != model:
        # Poses on the axes only, say, have no cross-axis terms to fit: judge with six.
        with suppress(CalibrationError):
            judge, judged = wider, solve_least_squares(poses, wider, limits, max_condition)
    worst = judged.quality.studentised_max_counts
    if worst is None or worst <= limit:
        return _judged(fit, judged, judge, limit)
    t = np.abs(judged.quality.studentised_counts)  # type: ignore[arg-type]
    n = len(poses)
    spare = n - UNKNOWNS[judge]
    head = (
        f"poses inconsistent: studentised residual {worst:.3g} counts > limit {limit:g} "
        f"({judge}-parameter model)"
    )
    hint = " (or cross-axis coupling: try the nine-parameter model)" if judge == "six" else ""
    if spare < EXCLUSION_MIN_SPARE:
        refuse_beyond_datasheet(poses, limits.sensor)  # the likelier cause, where one pose shows it
        raise InconsistentPosesError(
            f"{head}; with {n} poses ({spare} spare) one bad pose cannot be told from the "
            f"others{hint}: take the poses again, or add {EXCLUSION_MIN_SPARE - spare} or more"
        )
    worst_pose = int(np.argmax(t))
    try:
        found = _explained(poses, model, judge, limits, max_condition, limit, head)
    except _UnclearedPoseError as unchecked:
        refuse_beyond_datasheet(poses, limits.sensor)
        raise InconsistentPosesError(
            f"{head} at pose {worst_pose + 1}; without pose {unchecked.pose + 1} the other "
            f"poses cannot be fitted ({unchecked.reason}), so no pose can be cleared or "
            "blamed: take the poses again"
        ) from None
    if found is not None:
        return found
    raise InconsistentPosesError(
        f"{head} at pose {worst_pose + 1}, and leaving out any one pose does not explain "
        f"it: more than one pose is off (moved or mislabelled){hint}; take them again"
    )


class _UnclearedPoseError(Exception):
    """Leaving out ``pose`` left poses that could not be fitted for their geometry
    (``reason``, the refit's refusal): that pose cannot be cleared, so no other pose can be
    blamed in its place."""

    def __init__(self, pose: int, reason: str) -> None:
        super().__init__(pose, reason)
        self.pose = pose
        self.reason = reason


def _explained(
    poses: FloatArray,
    model: Model,
    judge: Model,
    limits: GeometryLimits,
    max_condition: float,
    limit: float,
    head: str,
) -> Solution | None:
    """The fit without the one pose whose leaving out leaves the rest consistent (judged
    with ``judge``, fitted with ``model``); None when no pose does.

    Every pose is left out in turn: a bad pose is excluded only when every other pose is
    cleared, its leaving out refitted and found inconsistent. The largest studentised
    residual is not enough to pick the candidates: on a cap-shaped set a large error
    moves the fit far from its linear picture, and the bad pose can rank below good ones.

    Raises:
        InconsistentPosesError: more than one pose does (named), or a pose no sensor
            could read is among the poses.
        _UnclearedPoseError: leaving out a pose left poses that could not be fitted for their
            geometry (a pose that spoils the fit of a sound geometry is not that).
    """
    n = len(poses)
    explained: list[tuple[int, Solution]] = []
    for candidate in range(n):
        keep = np.arange(n) != candidate
        try:
            refit = solve_least_squares(poses[keep], judge, limits, max_condition)
        except (CoplanarPosesError, DuplicatePoseError, TooFewPosesError) as refused:
            raise _UnclearedPoseError(candidate, str(refused)) from None  # untested
        except CalibrationError as refused:
            # On a sound geometry the rest still hold a pose that spoils their fit (or
            # that no sensor could read): this candidate is not the one. On a degenerate
            # one it cannot be told.
            try:
                refuse_degenerate_geometry(normalise(poses[keep]), judge, max_condition)
            except IllConditionedError:
                raise _UnclearedPoseError(candidate, str(refused)) from None
            continue
        if (refit.quality.studentised_max_counts or 0.0) <= limit:
            explained.append((candidate, refit))
    if len(explained) == 1:
        pose, refit = explained[0]
        keep = np.arange(n) != pose
        final = (
            refit
            if judge == model
            else solve_least_squares(poses[keep], model, limits, max_condition)
        )
        return _judged(_excluding(final, pose, poses), _excluding(refit, pose, poses), judge, limit)
    refuse_beyond_datasheet(poses, limits.sensor)
    if explained:
        named = " or ".join(f"pose {c + 1}" for c, _ in explained)
        raise InconsistentPosesError(
            f"{head}: {named} is off, and the poses cannot tell which: take them again",
            candidates=tuple(c for c, _ in explained),
        )
    return None


def _judged(fit: Solution, judged: Solution, judge: Model, limit: float) -> Solution:
    """``fit`` carrying the studentised residuals of the model that judged the poses."""
    quality = replace(fit.quality, studentised_counts=judged.quality.studentised_counts)
    return replace(fit, quality=quality, residual_limit_counts=limit, checked_with=judge)


def _excluding(refit: Solution, pose: int, poses: FloatArray) -> Solution:
    """``refit`` (over all poses but ``pose``) reported against all N poses."""
    q = refit.quality
    closest, other = (index + (index >= pose) for index in q.closest_pair)  # into all N
    studentised = None
    if q.studentised_counts is not None:
        studentised = np.insert(q.studentised_counts, pose, np.nan)
    quality = replace(
        q,
        pose_g=np.linalg.norm(apply(refit.calibration, poses), axis=1),
        closest_pair=(closest, other),
        studentised_counts=studentised,
    )
    return replace(refit, quality=quality, excluded=(pose,))
