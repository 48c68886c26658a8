"""One unit's run, stepped in-process against a virtual putter over a real pty."""

import time
import uuid
from collections.abc import Callable, Iterator
from dataclasses import replace
from datetime import UTC, datetime
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from station.device import DeviceCalibration, PutterDriver
from station.domain.product.limits import Bounds, LimitsProfile, load_profile
from station.domain.product.products import Product
from station.domain.product.run_settings import RunSettings
from station.domain.record.records import RunRecord
from station.domain.sensors.faults import Faults
from station.domain.sensors.sensor import ADC_MAX, OFFSET_TEMPCO_COUNTS_PER_C
from station.domain.signals.orientation import POSE_TOLERANCE_DEG, sense
from station.domain.signals.poses import POSES
from station.results.journal import JournalFile, RunJournal
from station.run.phases import Phase
from station.run.unit_run import UnitRun, open_unit
from station.simulator.putter import VirtualPutter
from station.simulator.sensor import SensorTruth, Thermal

SERIAL = "PT000077"


#: A hang guard, not a speed requirement: waits end on the samples, not on the clock.
HANG_S = 60.0


class Bench:
    """A virtual putter on a pty, a driver on it, and a run of that unit."""

    def __init__(
        self,
        tmp: Path,
        faults: Faults | None = None,
        seed: int = 11,
        settings: RunSettings | None = None,
        noise_counts: float | None = None,
        truth: SensorTruth | None = None,
        profile: LimitsProfile | None = None,
        product: Product | None = None,
        thermal: Thermal | None = None,
    ) -> None:
        self.putter = VirtualPutter(
            seed=seed,
            serial=SERIAL,
            speed=20.0,
            faults=faults,
            noise_counts=noise_counts,
            truth=truth,
            sensor=product.sensor if product else None,
            thermal=thermal,
        )
        self.adc_max = product.sensor.adc_max if product else ADC_MAX
        self.port = tmp / "putter"
        self.putter.serve_pty(self.port)
        settings = settings or RunSettings()
        self.journal_file = JournalFile(tmp / "journal.json")
        journal = RunJournal(
            run_id=uuid.uuid4(),
            serial=SERIAL,
            station_id="st",
            operator_id="op",
            started_at=datetime.now(UTC),
            poses=(*settings.poses, settings.verification_pose),
            **({"part_number": product.part_number} if product else {}),
        )
        self.run = UnitRun(
            driver=self.open(),
            journal=journal,
            journal_file=self.journal_file,
            profile=profile or load_profile(None, product.limits_profile if product else None),
            settings=settings,
            reopen=self.open,
        )
        self.moved_to: str | None = None
        #: Everything the run said, in order (its log keeps only the latest, and takes
        #: off the screen what is no longer true).
        self.said: list[str] = []

    def open(self) -> PutterDriver:
        return open_unit(str(self.port), SERIAL, self.adc_max)

    def drive(self, until: Callable[[UnitRun], bool], timeout: float = 60.0) -> None:
        """Step the run, moving the unit as asked, until ``until`` holds."""
        deadline = time.monotonic() + timeout
        while not until(self.run):
            assert time.monotonic() < deadline, [m.text for m in self.run.messages]
            target = self.run.requested
            if target is not None and target.name != self.moved_to and self.run.phase is Phase.POSE:
                self.moved_to = target.name
                self.putter.move_to(target.name, 1.0)
            seen = self.run.messages.said
            self.run.step()
            self.said += [m.text for m in self.run.messages.since(seen)]
            time.sleep(0.01)

    def close(self) -> None:
        self.run.driver.close()
        self.putter.close()


@pytest.fixture
def bench(tmp_path: Path) -> Iterator[Bench]:
    b = Bench(tmp_path)
    yield b
    b.close()


def done(run: UnitRun) -> bool:
    return run.phase is Phase.DONE


def test_a_pass_stores_coefficients_the_unit_holds(bench: Bench) -> None:
    bench.drive(done)
    record = bench.run.record
    assert record is not None
    assert record.verdict == "pass", record.failures
    assert [p.role for p in record.poses] == ["fit"] * 6 + ["verify"]
    stored = bench.putter.stored_calibration
    # The six-pose default never touches the gyros' coefficients (protocol extension).
    assert record.gyro_matrix is None
    assert bench.putter.stored_gyro_calibration == DeviceCalibration.gyro_default()
    assert record.coefficients is not None
    np.testing.assert_allclose(stored.offset, record.coefficients.offset.as_tuple(), rtol=1e-6)
    truth = bench.putter.truth
    np.testing.assert_allclose(record.coefficients.offset.as_tuple(), truth.offset_counts, atol=1.0)
    assert record.quality is not None
    assert record.quality.verification_error_mg is not None
    assert bench.run.unit_output_error_mg is not None
    assert record.gyro is not None
    assert record.gyro.still is not None
    # The virtual gyros have no bias-form g-sensitivity. A pose's gyro mean carries
    # about 0.01 deg/s of noise (0.3 deg/s over √1024 samples), so over poses 1 g apart
    # each slope is known to about 0.01 deg/s/g: all stay well under 0.1 deg/s/g.
    for axis in record.gyro.still.axes:
        assert axis.slope_dps_per_g is not None
        assert max(abs(v) for v in axis.slope_dps_per_g) < 0.1
    assert record.decision_rule == "simple"  # the shipped profile names no rule
    # Every coefficient carries its expanded uncertainty; the six-pose run has no K.
    assert record.uncertainty is not None
    shape = record.uncertainty.to_json()
    assert set(shape) == {
        "k",
        "offset",
        "sensitivity",
        "gyro_bias_dps",
        "verification_error_mg",
        "excluded_influences",
    }
    # The poses carry temperatures; the putter declares no gyro-bias repeatability.
    assert shape["excluded_influences"] == ["gyro_bias_repeatability"]
    assert shape["k"] == 2.0
    u = record.uncertainty
    assert u.offset is not None
    assert u.sensitivity is not None
    assert u.gyro_bias_dps is not None
    # 1024 samples of ~1 count noise: the offsets to a few hundredths of a count, plus
    # the drift the datasheet allows over the poses' temperatures (the virtual putter
    # warms while it waits, longer on a busy machine); the sensitivities carry the
    # six-parameter model's unmodelled cross-axis (~0.1-0.5).
    temperatures = [p.temperature_c for p in record.poses if p.temperature_c is not None]
    drift = OFFSET_TEMPCO_COUNTS_PER_C * (max(temperatures) - min(temperatures))
    assert all(0.0 < v < 0.2 + 2 * drift for v in u.offset.as_tuple())
    assert all(0.0 < v < 1.5 for v in u.sensitivity.as_tuple())
    assert all(0.0 < v < 0.05 for v in u.gyro_bias_dps)


def test_a_unit_at_the_datasheets_offset_bounds_is_taken_in_every_pose(tmp_path: Path) -> None:
    # Offsets at the KXM52's bounds (±207 counts): on nominal offsets alone the unit reads
    # more than the placement tolerance away from poses it lies in exactly, which once
    # left a fixture's slot waiting for ever.
    truth = replace(
        SensorTruth.draw(np.random.default_rng(5)),
        offset_counts=2048.0 + np.array([-205.0, 200.0, 205.0]),
        sensitivity_counts_per_g=np.array([781.0, 790.0, 781.0]),
    )
    settings = RunSettings()
    plan = (*settings.poses, settings.verification_pose)
    nominal = [sense(truth.still_counts(POSES[name].gravity_body[None, :])[0]) for name in plan]
    assert max(s.nearest_deg for s in nominal) > POSE_TOLERANCE_DEG  # the case at issue
    b = Bench(tmp_path, truth=truth)
    try:
        b.drive(done)
        assert b.run.record is not None
        assert b.run.record.verdict == "pass", b.run.record.failures
        refusals = [text for text in b.said if text.startswith(("wrong pose", "tilted"))]
        assert not refusals
    finally:
        b.close()


def test_a_wrong_pose_leaves_the_screen_once_the_unit_lies_in_the_pose_asked(
    tmp_path: Path,
) -> None:
    b = Bench(tmp_path)
    try:
        asked = b.run.requested
        assert asked is not None
        b.moved_to = asked.name  # the operator puts it elsewhere first
        b.putter.move_to("toe_up", 1.0)
        b.drive(lambda run: any(m.text.startswith("wrong pose") for m in run.messages))
        assert "wrong pose: the putter lies toe up, pose 1 is face up" in b.said
        b.putter.move_to(asked.name, 1.0)
        b.drive(lambda run: run.view().live.matches and run.view().live.progress > 0)
        assert b.run.requested == asked
        assert [m.text for m in b.run.messages if m.text.startswith("wrong pose")] == []
    finally:
        b.close()


def test_a_unit_inside_a_limit_but_within_u_of_it_passes_simple_and_fails_guarded(
    tmp_path: Path,
) -> None:
    # The same unit gives the same sensitivities run after run to a few hundredths of a
    # count/g (1,024 samples a pose), while their U, which holds the six-parameter
    # model's unmodelled cross-axis coupling, is tenths: a limit half a U above the
    # unit's x sensitivity is inside it, but within U of it, on every run. The sensor's
    # noise dithers its ADC and the board does not warm, so that U is the same on every
    # run: without noise the quantisation term follows whether the settling tremor left
    # in a window spreads the samples over half an LSB (U 0.24 or 0.37), and a warming
    # board's temperature term the wall-clock time a busy machine takes over the poses
    # (a first run's U once came out larger than the guarded run's, which then passed).
    unit = SensorTruth.draw(np.random.default_rng(8))
    truth = replace(unit, sensitivity_counts_per_g=np.array([840.0, 815.0, 805.0]))

    def run(name: str, profile: LimitsProfile | None = None) -> RunRecord:
        (tmp_path / name).mkdir()
        b = Bench(
            tmp_path / name, truth=truth, profile=profile, thermal=Thermal(self_heating_c=0.0)
        )
        try:
            b.drive(done)
            assert b.run.record is not None
            return b.run.record
        finally:
            b.close()

    first = run("first")
    assert first.verdict == "pass", first.failures
    assert first.coefficients is not None
    assert first.uncertainty is not None
    assert first.uncertainty.sensitivity is not None
    value, u = first.coefficients.sensitivity.x, first.uncertainty.sensitivity.x
    assert u > 0.1
    shipped = load_profile()
    limit = Bounds(lower=shipped.sensitivity_counts_per_g.lower, upper=value + u / 2)
    edge = shipped.model_copy(update={"sensitivity_counts_per_g": limit})

    # Each run's own unit: inside the limit, within its U of it.
    def inside_but_within_u(record: RunRecord) -> None:
        assert record.coefficients is not None
        assert record.uncertainty is not None
        assert record.uncertainty.sensitivity is not None
        u_run = record.uncertainty.sensitivity.x
        assert u_run == pytest.approx(u, rel=0.05)
        assert limit.upper - u_run < record.coefficients.sensitivity.x <= limit.upper

    simple = run("simple", edge)
    assert simple.decision_rule == "simple"
    inside_but_within_u(simple)
    assert simple.verdict == "pass", simple.failures
    guarded = run("guarded", edge.model_copy(update={"decision_rule": "guarded"}))
    assert guarded.decision_rule == "guarded"
    inside_but_within_u(guarded)
    assert guarded.verdict == "fail"
    assert [(f.code, f.axis) for f in guarded.failures] == [("sensitivity", "x")]
    assert guarded.failures[0].upper == limit.upper
    # The operator's words: inside the limit, but less than its U inside, by which rule.
    assert "within" in guarded.failures[0].message
    assert "guarded acceptance" in guarded.failures[0].message


def test_a_unit_left_lying_then_moved_within_one_poll_is_not_told_it_lies_in_a_pose_taken(
    bench: Bench,
) -> None:
    # A poll takes in a pass's samples: a quarter second, or seconds of a sped-up
    # simulator's. Left lying in the pose just taken for longer than a window, then moved
    # to the next, all within one poll: the still window from before the move is the unit
    # still lying where it was put, no mistake, and the operator is not told otherwise.
    bench.drive(lambda run: len(run.journal.captures) == 1)  # face up taken
    bench.putter.sleep(3.0)  # 1,500 samples still in face up: more than a window
    bench.putter.move_to("face_down", 1.0, wait=True)
    bench.moved_to = "face_down"
    bench.putter.sleep(0.5)
    deadline = time.monotonic() + HANG_S
    while bench.run.driver.pending() < 2_000:  # all of it in, for one poll to take
        assert time.monotonic() < deadline
        time.sleep(0.01)
    bench.run.step()
    bench.drive(lambda run: len(run.journal.captures) == 2)
    assert not [m.text for m in bench.run.messages if m.text.startswith("too close")]


def test_the_pose_asked_for_but_tilted_past_the_tolerance_is_refused_with_its_angle(
    bench: Bench,
) -> None:
    bench.drive(lambda run: len(run.journal.captures) == 1)  # face up: x and z measured
    tilted = POSES["face_down"].rotation * Rotation.from_euler("x", 33, degrees=True)
    bench.putter.move_to(tilted, 1.0)
    bench.moved_to = "face_down"  # the operator leaves it tilted

    def told(run: UnitRun) -> bool:
        return any(m.text.startswith("tilted:") for m in run.messages)

    bench.drive(told)
    said = next(m.text for m in bench.run.messages if m.text.startswith("tilted:"))
    angle = float(said.split("lies ")[1].split("°")[0])
    assert 28 <= angle <= 38, said
    assert said.endswith("from face down (25° allowed): lay it flat in its cradle")
    assert len(bench.run.journal.captures) == 1
    bench.moved_to = None  # now laid flat
    bench.drive(done)
    assert bench.run.record is not None
    assert bench.run.record.verdict == "pass", bench.run.record.failures


def test_a_move_inside_one_drained_block_is_seen(bench: Bench) -> None:
    # The live view judges everything a poll drains, not only its last samples: a quick
    # move made and finished between two polls still counts as the unit having moved.
    bench.drive(lambda run: len(run.journal.captures) == 1)  # face up taken
    tilted = POSES["face_down"].rotation * Rotation.from_euler("x", 33, degrees=True)
    bench.run.step()  # the samples before the move are taken in
    rate = bench.run.driver.rate_hz
    start_s = bench.putter.clock.now()
    first = bench.putter.move_to(tilted, 0.5)
    assert first is not None
    # Not polled until the link has received the move, its settling and half a second of
    # stillness (sequence numbers count from the stream's start, as the samples received
    # and lost do).
    until = first + round((bench.putter.settled_at_s - start_s) * rate) + 256
    deadline = time.monotonic() + 60.0
    while (link := bench.run.driver.stats).samples + link.lost_samples < until:
        assert time.monotonic() < deadline, link
        time.sleep(0.01)
    bench.run.step()  # one poll drains the whole move and the stillness after it
    said = [m.text for m in bench.run.messages if m.text.startswith("tilted:")]
    assert said, [m.text for m in bench.run.messages]
    assert bench.run.view().live.moving is False  # what the screen shows is the unit now


def test_adaptive_capture_stores_how_many_samples_each_pose_used(tmp_path: Path) -> None:
    adaptive = RunSettings(capture="adaptive")
    counts = {}
    for noise in (1.0, 3.0):
        where = tmp_path / f"noise{noise:g}"
        where.mkdir()
        bench = Bench(where, settings=adaptive, noise_counts=noise)
        try:
            bench.drive(done)
        finally:
            bench.close()
        record = bench.run.record
        assert record is not None
        assert record.verdict == "pass", record.failures
        counts[noise] = [p.sample_count for p in record.poses]
        floor, ceiling = adaptive.adaptive.floor_samples, adaptive.adaptive.ceiling_samples
        assert all(floor <= n <= ceiling for n in counts[noise])
    # The simulator's truth: 1 count of noise meets the budget at the floor (a pose
    # taken while the put-down tremor dies out may need a hop more), 3 counts need
    # about (3 / 0.124)² = 590 samples.
    assert sorted(counts[1.0])[3] == floor
    assert max(counts[1.0]) < 2 * floor < min(counts[3.0])


def test_the_journal_holds_every_pose_taken(bench: Bench) -> None:
    bench.drive(lambda run: len(run.journal.captures) >= 3)
    saved = bench.journal_file.load()
    assert saved is not None
    assert sorted(saved.captures) == [0, 1, 2]
    assert saved.next_pose == 3


def test_unplugged_while_writing_back_it_writes_again_once_back(bench: Bench) -> None:
    bench.drive(lambda run: run.phase is Phase.UNIT_OUTPUT)
    bench.putter.unplug()
    bench.drive(lambda run: run.phase is Phase.RECONNECT)
    bench.putter.replug()
    bench.drive(done)
    assert bench.run.record is not None
    assert bench.run.record.verdict == "pass", bench.run.record.failures


def test_redo_is_refused_once_the_coefficients_are_being_written(bench: Bench) -> None:
    bench.drive(lambda run: run.phase is Phase.UNIT_OUTPUT)
    bench.run.redo(2)
    assert bench.run.messages[-1].text.startswith("too late to redo")
    assert 2 in bench.run.journal.captures


def test_a_saturated_axis_fails_the_unit_at_once(tmp_path: Path) -> None:
    bench = Bench(tmp_path, faults=Faults(saturate_axis="y"))
    try:
        bench.drive(done, timeout=20)
        record = bench.run.record
        assert record is not None
        assert record.verdict == "fail"
        assert [(f.code, f.axis) for f in record.failures] == [("saturated", "y")]
    finally:
        bench.close()


def test_a_unit_that_never_settles_is_said_and_can_be_aborted(tmp_path: Path) -> None:
    bench = Bench(tmp_path, faults=Faults(never_settle=True))
    try:
        bench.drive(lambda run: any("not still" in m.text for m in run.messages), timeout=30)
        assert bench.run.abort() is None  # no pose taken: nothing to record
        assert bench.run.phase is Phase.DONE
    finally:
        bench.close()


def test_abort_after_a_redo_records_the_poses_still_held(bench: Bench) -> None:
    bench.drive(lambda run: len(run.journal.captures) >= 3)
    bench.run.redo(1)
    record = bench.run.abort()
    assert record is not None
    assert [p.name for p in record.poses] == ["face_up", "toe_up"]
    assert [p.index for p in record.poses] == [0, 1]
    assert [f.code for f in record.failures] == ["aborted"]


def test_another_unit_plugged_back_in_is_named_until_the_right_one_returns(
    bench: Bench, tmp_path: Path
) -> None:
    bench.drive(lambda run: len(run.journal.captures) >= 2)
    bench.putter.unplug()
    bench.drive(lambda run: run.phase is Phase.RECONNECT)
    other = VirtualPutter(seed=3, serial="PT000002", speed=20.0)
    other.serve_pty(bench.port)  # the operator plugs the wrong unit in
    try:
        bench.drive(lambda run: run.view().wrong_unit is not None, timeout=20)
        said = [m.text for m in bench.run.messages]
        assert said[-1] == (
            f"PT000002 plugged in, {SERIAL} expected: plug {SERIAL} back in, or abort"
        )
    finally:
        other.close()
    bench.putter.replug()
    bench.drive(lambda run: run.phase is Phase.POSE, timeout=20)
    assert bench.run.view().wrong_unit is None
    texts = [m.text for m in bench.run.messages]
    assert texts[-1] == "the unit is back: carry on"
    assert not any("PT000002" in t or "lost the unit" in t for t in texts)  # no longer true
    bench.drive(done)
    assert bench.run.record is not None
    assert bench.run.record.verdict == "pass"


def test_a_key_for_a_pose_not_taken_says_so_and_changes_nothing(bench: Bench) -> None:
    bench.drive(lambda run: len(run.journal.captures) >= 1)
    bench.run.redo(4)  # key 5 at pose 2
    assert bench.run.messages[-1].text == "pose 5 (shaft up) is not taken yet: nothing to redo"
    assert sorted(bench.run.journal.captures) == [0]
    assert 4 not in bench.run.journal.replaced


def test_an_abort_after_the_write_back_is_not_recorded_as_leaving_the_unit_alone(
    bench: Bench,
) -> None:
    bench.drive(lambda run: run.phase is Phase.UNIT_OUTPUT)
    record = bench.run.abort()
    assert record is not None
    assert [f.code for f in record.failures] == ["unit_output"]
    assert record.coefficients is not None  # and wrote_unit(record) holds: the unit has them


def test_a_capture_refused_for_link_loss_says_why_at_once(tmp_path: Path) -> None:
    bench = Bench(tmp_path, faults=Faults(drop_rate=0.05))
    try:
        bench.drive(lambda run: "cable" in (run.view().live.refused or ""), timeout=20)
        refused = bench.run.view().live.refused
        assert refused is not None
        assert refused.startswith("capture refused: the cable loses")
        assert not bench.run.journal.captures
        assert bench.run.phase is Phase.POSE  # long before the 30 s pose timeout
    finally:
        bench.close()
