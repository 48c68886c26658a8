"""The run record: the solve's part (what it found, which poses it left out), and its
times whatever the wall clock did."""

from datetime import UTC, datetime, timedelta
from uuid import uuid4

import numpy as np

from station.device import LinkCounters
from station.domain.calibration import solve
from station.domain.product.limits import load_profile
from station.domain.product.products import load_products
from station.domain.product.run_settings import RunSettings
from station.domain.record.records import FailureReason, PoseRecord, Vector3
from station.domain.sensors.record_bounds import ADC_SPAN
from station.domain.sensors.sensor_spec import PUTTER_SENSOR
from station.domain.signals.samples import SampleBlock
from station.results.journal import Capture, RunJournal
from station.run.acquisition import PoseResult
from station.run.record import (
    capture_of,
    pose_records,
    quality_metrics,
    run_record,
    uncertainty_record,
)
from station.simulator.recording import pose_means, six_directions, spread_directions
from station.simulator.sensor import SensorTruth


def test_a_pose_left_out_live_is_recorded_with_the_run() -> None:
    rng = np.random.default_rng(31)
    unit = SensorTruth.draw_accelerometer(rng, cross_axis=0.02)
    directions = spread_directions(12)
    poses = pose_means(unit, directions, 0.05, rng)
    poses[7] -= 80.0 * directions[7]  # the unit moved while pose 8 was taken
    quality = quality_metrics(solve(poses, "nine"), verification_error_mg=0.4)
    assert quality.excluded_poses == (7,)
    assert quality.residual_max_mg < 1.0  # over the poses kept


def test_a_clean_run_records_no_exclusion_field() -> None:
    rng = np.random.default_rng(32)
    poses = pose_means(SensorTruth.draw_accelerometer(rng), spread_directions(6), 0.05, rng)
    quality = quality_metrics(solve(poses), verification_error_mg=None)
    assert quality.excluded_poses is None
    assert "excluded_poses" not in quality.model_dump(exclude_none=True)


def _pose_result() -> PoseResult:
    n = 1024
    window = SampleBlock.from_columns(
        np.arange(n, dtype=np.float64),
        np.tile([2048.0, 2048.0, 2867.0], (n, 1)),
        np.zeros((n, 3)),
        np.full(n, 25.0),
    )
    return PoseResult(
        pose="face_up",
        summary=window.summary(),
        first_seq=0,
        last_seq=n - 1,
        duration_s=2.0,
        wait_s=2.0,
        loss_fraction=0.0,
        link=LinkCounters(),
    )


def test_a_clock_stepped_back_never_ends_a_run_before_it_began() -> None:
    """The wall clock stepped back an hour during the run (NTP, a technician): the run
    still ends no earlier than it began, so its record is valid and is stored."""
    started = datetime.now(UTC) + timedelta(hours=1)
    journal = RunJournal(
        run_id=uuid4(),
        serial="PT000001",
        station_id="st-1",
        operator_id="op-1",
        started_at=started,
        poses=("face_up",),
        captures={0: capture_of(_pose_result(), 0, "face_up", "fit", ())},
    )
    record = run_record(
        journal,
        RunSettings(),
        load_profile(),
        None,
        verdict="fail",
        failures=(FailureReason(code="aborted", message="aborted by the operator"),),
        disposition="retest",
        golden=False,
        verification_error_mg=None,
        gyro=None,
        poses=pose_records(journal.captures, None),
    )
    assert record.finished_at == started
    # The verdict records the rule that judged it: the profile's, simple by default.
    assert record.decision_rule == "simple"


def _captures(
    poses: np.ndarray, spread: float, count: int, temperatures: list[float] | None = None
) -> dict[int, Capture]:
    return {
        i: Capture(
            record=PoseRecord(
                index=i,
                name=f"p{i}",
                mean=Vector3.of(mean),
                std=Vector3.of([spread] * 3),
                sample_count=count,
                gyro_mean=Vector3.of([0.1, -0.2, 0.05]),
                temperature_c=None if temperatures is None else temperatures[i],
            ),
            gyro_std=Vector3.of([0.08] * 3),
            captured_at=datetime.now(UTC),
            duration_s=2.0,
            loss_fraction=0.0,
        )
        for i, mean in enumerate(poses)
    }


def test_the_record_carries_the_budget_or_none_when_it_is_beyond_what_a_record_holds() -> None:
    unit = SensorTruth.draw_accelerometer(np.random.default_rng(33))
    poses = unit.still_counts(six_directions())
    solution = solve(poses)
    quiet = uncertainty_record(_captures(poses, 1.0, 1024), 6, solution, None, PUTTER_SENSOR)
    assert quiet is not None
    assert set(quiet.to_json()) == {
        "k",
        "offset",
        "sensitivity",
        "gyro_bias_dps",
        "excluded_influences",
    }
    # What U leaves out is named: these captures carry no temperature, and the putter's
    # sensor declares no gyro-bias repeatability.
    assert quiet.excluded_influences == ("temperature", "gyro_bias_repeatability")
    declared = PUTTER_SENSOR.model_copy(update={"gyro_bias_repeatability_dps": 0.05})
    told = uncertainty_record(_captures(poses, 1.0, 1024), 6, solution, None, declared)
    assert told is not None
    assert told.excluded_influences == ("temperature",)
    assert quiet.gyro_bias_dps is not None
    assert told.gyro_bias_dps is not None
    assert all(
        b > max(a, 2 * 0.05) for a, b in zip(quiet.gyro_bias_dps, told.gyro_bias_dps, strict=True)
    )
    assert quiet.offset is not None
    assert max(quiet.offset.as_tuple()) < 0.2
    # A spread of nearly the widest ADC's span in one sample a pose: U beyond that span,
    # which no record holds; the run is recorded without it rather than lost.
    assert (
        uncertainty_record(_captures(poses, 0.9 * ADC_SPAN, 1), 6, solution, None, PUTTER_SENSOR)
        is None
    )
    assert uncertainty_record(_captures(poses, 1.0, 1024), 6, None, None, PUTTER_SENSOR) is None


def test_the_temperature_term_follows_the_products_sensors_datasheet() -> None:
    # The same poses taken while the unit warmed 2 °C: the offsets' U grows with the
    # temperature coefficient the product's sensor allows, and only the drift differs.
    unit = SensorTruth.draw_accelerometer(np.random.default_rng(34))
    poses = unit.still_counts(six_directions())
    captures = _captures(poses, 1.0, 1024, [25.0 + 0.4 * i for i in range(6)])
    solution = solve(poses)

    def offset_u(offset_tempco_g_per_c: float) -> float:
        sensor = PUTTER_SENSOR.model_copy(update={"offset_tempco_g_per_c": offset_tempco_g_per_c})
        found = uncertainty_record(captures, 6, solution, None, sensor)
        assert found is not None
        assert found.offset is not None
        return max(found.offset.as_tuple())

    still = offset_u(0.0)
    putter = offset_u(PUTTER_SENSOR.offset_tempco_g_per_c)
    assert still < putter < offset_u(10 * PUTTER_SENSOR.offset_tempco_g_per_c)
    d16 = load_products().products["DIXX-D16"].sensor
    assert d16.offset_tempco_counts_per_c == d16.offset_tempco_g_per_c * d16.counts_per_g
