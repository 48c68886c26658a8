"""K and the bias recovered from synthetic streams with known truth ([Tedaldi2014])."""

import functools

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from station.domain.gyro.motion import GyroMatrixError, Move, calibrate_stream, fit_gyro_matrix
from station.simulator.recording import (
    StreamPlan,
    k_in_calibrated_frame,
    pose_orientations,
    random_imu,
    recorded_stream,
    spread_directions,
)
from station.simulator.sensor import SensorTruth

#: Small and fast: 200 samples/s, 1.5 s stills, 1 s moves.
PLAN = StreamPlan(rate_hz=200.0, still_s=1.5, move_s=1.0)
QUIET = StreamPlan(
    rate_hz=200.0, still_s=1.5, move_s=1.0, accel_noise_counts=0.0, gyro_noise_dps=0.0
)
#: What the integration itself may leave at 200 samples/s (trapezoid steps, 1 s turns).
INTEGRATION_FLOOR = 1e-4


def _unit_and_stream(seed: int, plan: StreamPlan, poses: int = 12) -> tuple[SensorTruth, object]:
    rng = np.random.default_rng(seed)
    imu = random_imu(rng)
    return imu, recorded_stream(rng, imu, pose_orientations(rng, spread_directions(poses)), plan)


@settings(max_examples=6, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_noise_free_stream_gives_k_to_the_integration_floor(seed: int) -> None:
    imu, stream = _unit_and_stream(seed, QUIET)
    result = calibrate_stream(stream, "nine")  # type: ignore[arg-type]
    assert len(result.stills) == 12
    error = result.gyro.scale_matrix - k_in_calibrated_frame(imu, "nine")
    assert np.abs(error).max() < INTEGRATION_FLOOR
    assert np.allclose(result.bias_dps, imu.gyro_bias_dps, atol=1e-12)


@settings(max_examples=6, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_noisy_stream_gives_k_within_its_standard_errors(seed: int) -> None:
    """Errors within 5 σ of the fit's own standard errors (plus the integration floor);
    the bias within 5 σ of the gyro noise over the still samples."""
    imu, stream = _unit_and_stream(seed, PLAN)
    result = calibrate_stream(stream, "nine")  # type: ignore[arg-type]
    se = result.gyro.standard_errors
    error = np.abs(result.gyro.scale_matrix - k_in_calibrated_frame(imu, "nine"))
    assert (error <= 5 * se + INTEGRATION_FLOOR).all(), (error, se)
    still_samples = sum(len(s) for s in result.stills)
    bias_sigma = PLAN.gyro_noise_dps / np.sqrt(still_samples)
    assert np.abs(result.bias_dps - imu.gyro_bias_dps).max() < 5 * bias_sigma
    # The fit explains the moves far better than no gyro calibration does.
    assert result.gyro.residual_rms_deg < 0.1
    assert np.median(result.gyro.residual_identity_deg) > 5 * result.gyro.residual_rms_deg


def test_six_parameter_accelerometer_skews_k_on_cross_axis_units() -> None:
    """2 % cross-axis: the six-parameter gravity directions leave K far off."""
    imu, stream = _unit_and_stream(5, PLAN)
    six = calibrate_stream(stream, "six")  # type: ignore[arg-type]
    nine = calibrate_stream(stream, "nine")  # type: ignore[arg-type]
    error_six = np.abs(six.gyro.scale_matrix - k_in_calibrated_frame(imu, "six")).max()
    error_nine = np.abs(nine.gyro.scale_matrix - k_in_calibrated_frame(imu, "nine")).max()
    assert error_six > 10 * error_nine


@functools.cache
def _calibrated(seed: int) -> tuple[tuple[Move, ...], np.ndarray]:
    imu, stream = _unit_and_stream(seed, QUIET, poses=9)
    result = calibrate_stream(stream, "nine")  # type: ignore[arg-type]
    return tuple(result.moves), imu.gyro_bias_dps


def _moves_of(seed: int) -> tuple[list[Move], np.ndarray]:
    moves, bias = _calibrated(seed)
    return list(moves), bias


#: The most samples a generated gap removes.
MAX_LOST = 20


def _gap(samples: int, where: float, lost: int) -> tuple[int, int]:
    """The samples ``[start, end)`` a gap of ``lost`` samples removes from a move of
    ``samples``, ``where`` (0…1) along it: strictly inside, a sample kept on each side."""
    start = 1 + int(where * (samples - 2 - lost))
    return start, start + lost


@given(
    samples=st.integers(2 + MAX_LOST, 10_000),
    where=st.floats(0.0, 1.0),
    lost=st.integers(1, MAX_LOST),
)
@example(samples=310, where=0.949, lost=17)  # once drawn as the move's last 17 samples
def test_a_generated_gap_lies_strictly_inside_its_move(
    samples: int, where: float, lost: int
) -> None:
    start, end = _gap(samples, where, lost)
    assert start >= 1
    assert end - start == lost
    assert end <= samples - 1


@settings(max_examples=10, deadline=None)
@given(
    seed=st.integers(0, 1),
    which=st.integers(0, 7),
    where=st.floats(0.0, 1.0),
    lost=st.integers(1, MAX_LOST),
)
@example(seed=0, which=0, where=0.949, lost=17)  # a gap that once took the move's end
@example(seed=1, which=7, where=1.0, lost=MAX_LOST)  # the latest gap, in a shorter move
def test_a_gap_makes_that_move_unusable_and_says_so(
    seed: int, which: int, where: float, lost: int
) -> None:
    moves, bias = _moves_of(seed)
    move = moves[which]
    start, end = _gap(len(move.t), where, lost)
    gapped = Move(
        t=np.concatenate([move.t[:start], move.t[end:]]),
        rates_dps=np.concatenate([move.rates_dps[:start], move.rates_dps[end:]]),
        gravity_before=move.gravity_before,
        gravity_after=move.gravity_after,
    )
    moves[which] = gapped
    fit = fit_gyro_matrix(moves, bias)
    assert [u.index for u in fit.unusable] == [which]
    assert "gap" in fit.unusable[0].reason
    assert which not in fit.used
    assert len(fit.residual_deg) == len(moves) - 1


def test_too_few_usable_moves_refuse_naming_them() -> None:
    moves, bias = _moves_of(0)
    broken = [
        Move(m.t[::-1], m.rates_dps, m.gravity_before, m.gravity_after) if i < 4 else m
        for i, m in enumerate(moves)
    ]
    with pytest.raises(GyroMatrixError, match=r"needs 6 usable moves, got 4 of 8.*move 0: time"):
        fit_gyro_matrix(broken, bias)


def test_moves_about_one_axis_do_not_determine_k() -> None:
    """Turns about body z only: the x/y columns of K are not seen."""
    t = np.linspace(0.0, 1.0, 201)
    moves = []
    for angle in (0.5, -1.0, 1.5, -0.7, 1.2, -0.4):
        rates = np.tile(np.degrees([0.0, 0.0, angle]), (201, 1))
        before = np.array([1.0, 0.0, 0.0])
        c, s = np.cos(angle), np.sin(angle)
        after = np.array([c, -s, 0.0])
        moves.append(Move(t, rates, before, after))
    with pytest.raises(GyroMatrixError, match="too few axes"):
        fit_gyro_matrix(moves, np.zeros(3))


def test_five_moves_are_refused_unless_asked_for() -> None:
    moves, bias = _moves_of(0)
    with pytest.raises(GyroMatrixError, match="needs 6 usable moves, got 5 of 5"):
        fit_gyro_matrix(moves[:5], bias)
    assert len(fit_gyro_matrix(moves[:5], bias, min_moves=5).used) == 5
    with pytest.raises(ValueError, match="no degree of freedom"):
        fit_gyro_matrix(moves, bias, min_moves=4)


def _turns_about_x_and_z_only() -> Rotation:
    """Eight poses joined by turns about body x and z only: a y rotation is never seen
    except in a whole turn about the vertical while y points up (pose 1)."""
    steps = [("x", 0), ("x", 90), ("z", 90), ("z", 180), ("z", 90), ("x", 90), ("x", 90), ("z", 90)]
    poses = [Rotation.identity()]
    for axis, deg in steps[1:]:
        poses.append(poses[-1] * Rotation.from_euler(axis, deg, degrees=True))
    return Rotation.concatenate(poses)


@pytest.mark.parametrize("seed", [7, 8])
def test_a_declared_whole_turn_gives_the_rotation_gravity_cannot_see(seed: int) -> None:
    rng = np.random.default_rng(seed)
    truth = random_imu(rng, cross_axis=0.0)
    stream = recorded_stream(
        rng, truth, _turns_about_x_and_z_only(), StreamPlan(wobble_deg=1.0), turns={1: 360.0}
    )
    true_k = k_in_calibrated_frame(truth, "six")
    blind = calibrate_stream(stream, "six").gyro
    known = calibrate_stream(stream, "six", known_turn_deg=360.0).gyro
    assert blind.known_turns == ()
    assert known.known_turns == (1,)  # the move after pose 1, and no other
    assert abs(known.known_turn_swept_deg[0] - 360.0) < 0.5
    # The turn's angle gives the scale about its axis (y here), which gravity cannot see;
    # its axis is left free (a hand's turn is not exactly about the vertical), so how a
    # y rotation leaks into the other gyros stays as the gravity directions give it.
    error_blind = abs(blind.scale_matrix[1, 1] - true_k[1, 1])
    error_known = abs(known.scale_matrix[1, 1] - true_k[1, 1])
    assert error_blind > 4e-4  # the case at issue: the y scale unseen without the turn
    assert error_known < 1e-4
    assert error_known < error_blind / 4


@pytest.mark.parametrize("seed", [7, 8])
def test_a_hand_s_turn_a_degree_off_the_vertical_does_not_pull_k_off(seed: int) -> None:
    # imucal's hand-held turns sweep about axes 0.4–0.9° off the vertical. Holding the
    # turn's summed rotation vector to the vertical (three equations a turn) threw K off
    # by 0.016 here; the swept angle alone keeps it where the moves put it.
    rng = np.random.default_rng(seed)
    truth = random_imu(rng, cross_axis=0.0)
    plan = StreamPlan(wobble_deg=1.0, turn_tilt_deg=1.0)
    stream = recorded_stream(rng, truth, _turns_about_x_and_z_only(), plan, turns={1: 360.0})
    known = calibrate_stream(stream, "six", known_turn_deg=360.0).gyro
    true_k = k_in_calibrated_frame(truth, "six")
    assert known.known_turns == (1,)
    assert abs(known.known_turn_swept_deg[0] - 360.0) < 0.5
    assert abs(known.scale_matrix[1, 1] - true_k[1, 1]) < 2e-4
    assert float(np.abs(known.scale_matrix - true_k).max()) < 4e-3
