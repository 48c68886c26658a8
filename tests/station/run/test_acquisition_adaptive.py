"""Adaptive capture: windows end at the accuracy budget, on streams with known noise."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from station.device import PutterDriver
from station.domain.calibration import solve
from station.domain.product.capture_budget import (
    CRB_SENSITIVITY_PER_SIGMA,
    AdaptiveCapture,
    WindowPolicy,
    pose_budget_counts,
)
from station.domain.product.limits import Bounds, load_profile
from station.domain.signals.poses import CALIBRATION_POSES, pose
from station.domain.signals.samples import SampleBlock
from station.run.acquisition import StillnessDetector, StillnessThresholds, acquire_pose
from station.simulator import VirtualPutter
from tests.conftest import examples

LIMITS = StillnessThresholds()
PROFILE = load_profile()
SETTINGS = AdaptiveCapture()
POLICY = WindowPolicy.adaptive(SETTINGS, PROFILE)
BUDGET = POLICY.budget_counts
#: The six poses' gravity in body axes: the octahedron of the station's default plan.
GRAVITY = np.array([pose(name).gravity_body for name in CALIBRATION_POSES])


def still_stream(
    rng: np.random.Generator,
    reading: np.ndarray,
    noise: float,
    count: int,
    step_at: int | None = None,
    step_counts: float = 0.0,
) -> SampleBlock:
    """``count`` samples of a unit lying still at ``reading`` with white noise ``noise``.

    From sample ``step_at`` on the unit lies ``step_counts`` further on x (it was nudged).
    """
    accel = reading + rng.normal(0.0, noise, (count, 3))
    if step_at is not None:
        accel[step_at:, 0] += step_counts
    return SampleBlock.from_columns(
        np.arange(count, dtype=np.float64),
        np.rint(accel),
        rng.normal(0.0, 0.08, (count, 3)),
        np.full(count, 25.0),
    )


def first_window(stream: SampleBlock, policy: WindowPolicy) -> SampleBlock:
    verdict = StillnessDetector(LIMITS, policy).feed(stream)
    assert verdict is not None
    return verdict.window


def test_the_budget_follows_the_profiles_limit_widths() -> None:
    # Sensitivity binds for the shipped profile: 1/400 of 81.92 counts/g over 1.653.
    assert pytest.approx(0.0025 * 81.92 / CRB_SENSITIVITY_PER_SIGMA) == BUDGET
    wide = PROFILE.model_copy(update={"sensitivity_counts_per_g": Bounds(lower=100, upper=2000)})
    assert pose_budget_counts(wide, 0.0025) == pytest.approx(0.0025 * 414 / 0.897)
    open_ended = wide.model_copy(
        update={"offset_counts": Bounds(lower=1800), "sensitivity_counts_per_g": Bounds(upper=900)}
    )
    assert pose_budget_counts(open_ended, 0.0025) == math.inf


@given(
    std=st.lists(st.floats(0.01, 50.0), min_size=3, max_size=3),
    floor=st.integers(64, 2048),
    extra=st.integers(0, 4096),
    budget=st.floats(0.01, 5.0),
)
@settings(max_examples=examples(200), deadline=None)
def test_the_samples_a_spread_needs_end_the_window_between_floor_and_ceiling(
    std: list[float], floor: int, extra: int, budget: float
) -> None:
    policy = WindowPolicy(floor, floor + extra, budget)
    spread = np.array(std)
    need = policy.samples_needed(spread)
    assert floor <= need <= floor + extra
    assert policy.enough(spread, need)
    assert not policy.enough(spread, floor - 1)
    if floor < need < floor + extra:
        assert not policy.enough(spread, need - 1)


def test_with_floor_and_ceiling_equal_the_detector_is_the_fixed_one() -> None:
    rng = np.random.default_rng(1)
    stream = still_stream(rng, np.array([2048.0, 2048.0, 2867.0]), 1.0, 3000, 700, 8.0)
    fixed = first_window(stream, WindowPolicy.fixed(1024))
    default = StillnessDetector(LIMITS).feed(stream)
    assert default is not None
    np.testing.assert_array_equal(fixed.seq, default.window.seq)
    assert len(fixed) == 1024
    assert fixed.seq[0] > 0


@pytest.mark.parametrize("noise", [0.5, 1.5, 2.5, 3.5])
def test_a_window_ends_between_floor_and_ceiling_at_the_budget(noise: float) -> None:
    rng = np.random.default_rng(int(noise * 10))
    window = first_window(
        still_stream(rng, np.array([2048.0, 2048.0, 2867.0]), noise, 6000), POLICY
    )
    count = len(window)
    assert SETTINGS.floor_samples <= count <= SETTINGS.ceiling_samples
    error = window.accel.std(axis=0, ddof=1).max() / math.sqrt(count)
    if count < SETTINGS.ceiling_samples:
        assert error <= BUDGET
    if count > SETTINGS.floor_samples:
        # A hop earlier the window was not yet good enough (or not judged still).
        shorter = window[: count - LIMITS.hop_samples]
        assert shorter.accel.std(axis=0, ddof=1).max() / math.sqrt(len(shorter)) > BUDGET
    # Known truth: the rounded noise's variance is σ² + 1/12; the window ends near
    # (σ_eff / budget)², within the spread of the estimate and one hop.
    expected = (math.sqrt(noise**2 + 1 / 12) / BUDGET) ** 2
    low, high = SETTINGS.floor_samples, SETTINGS.ceiling_samples
    assert min(high, max(low, 0.8 * expected)) <= count
    assert count <= min(high, max(low, 1.2 * expected + LIMITS.hop_samples))


def test_a_window_still_short_of_the_budget_ends_at_the_ceiling() -> None:
    rng = np.random.default_rng(4)
    tight = WindowPolicy(256, 640, BUDGET / 10)
    window = first_window(still_stream(rng, np.array([2048.0, 2048.0, 2867.0]), 2.0, 3000), tight)
    assert len(window) == 640
    assert window.seq[0] == 0


def test_a_noisier_unit_takes_more_samples() -> None:
    counts = []
    for noise in (1.0, 2.0, 2.5, 3.5):
        rng = np.random.default_rng(7)
        stream = still_stream(rng, np.array([2048.0, 1229.0, 2048.0]), noise, 6000)
        counts.append(len(first_window(stream, POLICY)))
    assert counts == sorted(counts)
    assert counts[0] == SETTINGS.floor_samples
    assert counts[-1] > 3 * counts[0]


def test_a_unit_nudged_during_a_growing_window_is_refused_and_captured_after() -> None:
    rng = np.random.default_rng(3)
    # 3 counts of noise need ~600 samples; a 6-count nudge (0.4 degree) at sample 450
    # lies inside the growing window, whose last 64 samples alone look still.
    stream = still_stream(rng, np.array([2048.0, 2048.0, 2867.0]), 3.0, 6000, 450, 6.0)
    window = first_window(stream, POLICY)
    assert window.seq[0] > 400
    assert len(window) >= SETTINGS.floor_samples
    detector = StillnessDetector(LIMITS, POLICY)
    assert detector.feed(stream[:520]) is None


@pytest.mark.timeout(60)
def test_calibration_with_adaptive_windows_stays_within_the_budget() -> None:
    """Monte Carlo with known truth: 150 units, noise 2–3.5 counts, so the budget binds.

    The budget promises a sensitivity error of at most ``fraction · width`` (1σ) from
    the noise, with the Cramér–Rao factor of a generic six-pose spread (1.653). The
    station's axis-aligned poses do better: each sensitivity is half the difference of
    two pose means, σ_mean/√2, so windows ending at the budget give about 0.124/√2 =
    0.088 counts/g (the RMS over 450 axis values is known to ±3.3 %). Windows of the
    floor alone would give up to 3.5/16/√2 = 0.15; windows at the ceiling 0.03.
    """
    rng = np.random.default_rng(2026)
    offset_errors, sensitivity_errors, counts = [], [], []
    for _ in range(150):
        offset = 2048 + rng.uniform(-150, 150, 3)
        sensitivity = 819.2 * (1 + rng.uniform(-0.04, 0.04, 3))
        noise = rng.uniform(2.0, 3.5)
        means = []
        for gravity in GRAVITY:
            window = first_window(
                still_stream(rng, offset + sensitivity * gravity, noise, 6000), POLICY
            )
            counts.append(len(window))
            means.append(window.accel.mean(axis=0))
        calibration = solve(np.array(means), "six").calibration
        offset_errors.extend(calibration.offset - offset)
        sensitivity_errors.extend(calibration.sensitivity - sensitivity)
    rms_offset = math.sqrt(np.mean(np.square(offset_errors)))
    rms_sensitivity = math.sqrt(np.mean(np.square(sensitivity_errors)))
    fraction = SETTINGS.budget_fraction
    assert rms_sensitivity <= 1.15 * fraction * 81.92
    assert rms_offset <= 1.15 * fraction * 414.0
    # Known truth for these poses: the windows end at the budget, neither short of it
    # (floor only) nor far beyond it (the ceiling).
    assert 0.8 * BUDGET / math.sqrt(2) / 1.15 < rms_sensitivity <= 1.15 * BUDGET / math.sqrt(2)
    assert max(counts) < SETTINGS.ceiling_samples


@pytest.mark.timeout(60)
def test_the_virtual_putter_at_high_speed_gives_windows_to_its_noise() -> None:
    counts = {}
    for noise in (1.0, 3.0):
        with VirtualPutter(seed=5, speed=25.0, noise_counts=noise) as unit:
            url = unit.serve_pty()
            with PutterDriver.open(url) as driver:
                driver.start_stream()
                moved_at = unit.move_to("toe_up", 1.0)
                assert moved_at is not None
                result = acquire_pose(
                    driver, pose="toe_up", timeout_s=20.0, from_seq=moved_at, policy=POLICY
                )
        counts[noise] = result.summary.count
        assert SETTINGS.floor_samples <= result.summary.count <= SETTINGS.ceiling_samples
        # Known truth: white noise σ (plus rounding) needs (σ_eff / budget)² samples; the
        # put-down tremor's tail may add to the spread, never take from it.
        expected = (noise**2 + 1 / 12) / BUDGET**2
        assert 0.8 * expected <= result.summary.count
        assert result.summary.count <= max(SETTINGS.floor_samples, 1.4 * expected) + 64
    assert counts[3.0] > 2 * counts[1.0]
