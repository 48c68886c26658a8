"""The driver against the virtual putter over a real pty and a real socket."""

import socket
import threading
import time
from collections.abc import Iterator

import numpy as np
import pytest
import serial
from hypothesis import given, settings
from hypothesis import strategies as st

from station.device import (
    DeviceCalibration,
    DeviceDisconnectedError,
    DeviceRejectedError,
    DeviceTimeoutError,
    Identity,
    NoReplyError,
    ProtocolError,
    PutterDriver,
    SerialNumberMismatchError,
)
from station.device.protocol import FrameType, encode_frame, encode_sample
from station.domain.signals.poses import pose
from station.domain.signals.samples import SampleBlock
from station.simulator import VirtualPutter
from station.simulator.putter import FIRMWARE_VERSION, SENSOR_PART
from tests.conftest import examples

SPEED = 20.0

#: A hang guard, not a speed requirement: waits end on the samples, not on the clock.
HANG_S = 60.0


@pytest.fixture(params=["pty", "socket"])
def transport(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.fixture
def unit(transport: str) -> Iterator[VirtualPutter]:
    with VirtualPutter(seed=11, serial="PT000042", speed=SPEED) as putter:
        if transport == "pty":
            putter.serve_pty()
        else:
            putter.serve_socket()
        yield putter


@pytest.fixture
def driver(unit: VirtualPutter) -> Iterator[PutterDriver]:
    assert unit.url is not None
    with PutterDriver.open(unit.url, reply_timeout=0.3) as drv:
        yield drv


def static_reading(unit: VirtualPutter, name: str) -> np.ndarray:
    truth = unit.truth
    force = pose(name).gravity_body
    return truth.offset_counts + truth.sensitivity_counts_per_g * (truth.cross_axis @ force)


def test_identify_reports_serial_firmware_and_part(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    identity = driver.identify(expected_serial="PT000042")
    assert (identity.serial, identity.firmware, identity.sensor_part) == (
        "PT000042",
        FIRMWARE_VERSION,
        SENSOR_PART,
    )
    assert identity.protocol_version == 1


def test_stream_delivers_contiguous_samples_that_match_the_truth(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    driver.start_stream()
    rows = driver.wait_samples(3000, timeout=HANG_S)
    np.testing.assert_array_equal(rows.seq, np.arange(3000))
    np.testing.assert_allclose(rows.accel.mean(axis=0), static_reading(unit, "face_up"), atol=0.5)
    # Still: the gyros read their bias (g-sensitivity needs a rate, paper 2).
    np.testing.assert_allclose(rows.gyro.mean(axis=0), unit.truth.gyro_bias_dps, atol=0.02)
    assert 24.0 < rows.temperature.mean() < 28.0
    driver.stop_stream()
    stats = driver.stats
    assert stats.samples >= 3000
    assert stats.lost_samples == stats.crc_errors == stats.resyncs == 0


def test_set_rate_changes_the_device_time_between_samples(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    driver.set_rate(200)
    assert driver.rate_hz == 200
    start = unit.clock.now()
    driver.start_stream()
    block = driver.wait_samples(1000, timeout=HANG_S)
    elapsed = unit.clock.now() - start
    # Samples 0…last were made within ``elapsed`` of the unit's time: at 200 samples/s
    # at most 200·elapsed + 1 of them (at the old 500, 2.5 times as many). Reading late
    # only makes ``elapsed`` longer, so a busy machine cannot fail this.
    assert int(block.seq.max()) + 1 <= 200 * elapsed + 1


def test_the_unit_refuses_a_rate_out_of_range(driver: PutterDriver) -> None:
    with pytest.raises(DeviceRejectedError, match="SET_RATE: BAD_VALUE: rate 5000") as info:
        driver.set_rate(5000)
    assert info.value.code == 3
    assert driver.rate_hz == 500


def test_calibration_written_is_read_back_and_applied_in_calibrated_mode(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    assert driver.read_calibration() == DeviceCalibration.factory_default()
    truth = unit.truth
    written = DeviceCalibration(truth.offset_counts, truth.matrix)
    driver.write_calibration(written)
    back = driver.read_calibration()
    assert back.written
    np.testing.assert_array_equal(back.offset, written.offset)
    np.testing.assert_array_equal(back.matrix, written.matrix)
    driver.start_stream(calibrated=True)
    rows = driver.wait_samples(2000, timeout=HANG_S, calibrated=True)
    # The unit applies its calibration: a still unit reads gravity, within noise/temperature.
    np.testing.assert_allclose(rows.accel.mean(axis=0), pose("face_up").gravity_body, atol=3e-3)
    assert len(driver.drain()) == 0


def test_gyro_coefficients_are_read_back_and_applied_to_the_calibrated_gyros(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    assert driver.read_gyro_calibration() == DeviceCalibration.gyro_default()
    bias = unit.truth.gyro_bias_dps + np.array([0.1, -0.2, 0.3])
    inverse_k = np.array([[2.0, 0.0, 0.0], [0.0, 1.0, 0.5], [0.0, 0.0, 0.5]])
    written = DeviceCalibration(bias, inverse_k)
    driver.write_gyro_calibration(written)
    assert driver.read_gyro_calibration() == written
    # The accelerometer's coefficients are another set: untouched.
    assert driver.read_calibration() == DeviceCalibration.factory_default()
    driver.start_stream(calibrated=True)
    rows = driver.wait_samples(2000, timeout=HANG_S, calibrated=True)
    # Still, the gyros read their true bias: the unit reports K⁻¹·(bias − written bias).
    expected = inverse_k @ (unit.truth.gyro_bias_dps - bias)
    np.testing.assert_allclose(rows.gyro.mean(axis=0), expected, atol=0.02)
    driver.stop_stream()
    driver.start_stream()
    raw = driver.wait_samples(2000, timeout=HANG_S)
    np.testing.assert_allclose(raw.gyro.mean(axis=0), unit.truth.gyro_bias_dps, atol=0.02)


def test_a_mute_unit_gives_no_reply_after_the_retries(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    unit.faults.mute = True
    started = time.monotonic()
    with pytest.raises(NoReplyError, match=r"did not answer IDENTIFY within 0.3 s \(2 tries\)"):
        driver.identify()
    # Two tries of 0.3 s each: at least that long (longer on a busy machine).
    assert time.monotonic() - started >= 0.6


def test_a_unit_with_the_wrong_serial_is_refused(unit: VirtualPutter, driver: PutterDriver) -> None:
    unit.faults.serial_mismatch = True
    with pytest.raises(SerialNumberMismatchError, match="label says 'PT000042', unit reports"):
        driver.identify(expected_serial=unit.label_serial)


def test_pulling_the_cable_keeps_every_sample_taken_then_says_disconnected(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    # The cable goes once the station holds 1,000 samples, whatever the reader's pace.
    driver.start_stream()
    taken = [driver.wait_samples(1000, timeout=HANG_S)]
    unit.unplug()
    deadline = time.monotonic() + HANG_S
    failure: DeviceDisconnectedError | None = None
    while failure is None and time.monotonic() < deadline:
        try:
            taken.append(driver.drain())
        except DeviceDisconnectedError as exc:
            failure = exc
        time.sleep(0.01)
    assert failure is not None
    assert "disconnected" in str(failure)
    rows = SampleBlock.concat(taken)
    # Bytes in flight when the cable goes are lost; every sample received is handed out.
    assert len(rows) == driver.stats.samples >= 1000
    np.testing.assert_array_equal(rows.seq, np.arange(len(rows)))
    assert not driver.connected
    with pytest.raises(DeviceDisconnectedError):
        driver.identify()


def test_a_unit_opened_again_hands_out_none_of_the_stream_it_sent_before() -> None:
    # An earlier run ended on a saturated axis without stopping the stream (the station
    # just closes the port): the unit streamed its rail counts into the port for a
    # second more. Repaired on the same cable, the next run's stream is its own: from 0,
    # off the rail.
    with VirtualPutter(seed=11, serial="PT000042", speed=SPEED) as unit:
        url = unit.serve_pty()
        unit.faults.saturate_axis = "x"
        with PutterDriver.open(url) as earlier:
            earlier.start_stream()
            assert (earlier.wait_samples(100, timeout=HANG_S).accel[:, 0] == 4095).all()
        unit.sleep(1.0)
        unit.faults.saturate_axis = None
        with PutterDriver.open(url) as driver:
            driver.identify(expected_serial="PT000042")
            driver.start_stream()
            rows = driver.wait_samples(1000, timeout=HANG_S)
    np.testing.assert_array_equal(rows.seq, np.arange(1000))
    np.testing.assert_allclose(rows.accel.mean(axis=0), static_reading(unit, "face_up"), atol=0.5)


def test_after_a_replug_the_unit_answers_again(unit: VirtualPutter, driver: PutterDriver) -> None:
    driver.start_stream()
    driver.wait_samples(100, timeout=2.0)
    unit.unplug()
    with pytest.raises(DeviceDisconnectedError):
        driver.wait_samples(10**6, timeout=2.0)
    url = unit.replug()
    with PutterDriver.open(url) as again:
        assert again.identify().serial == "PT000042"


def stream_then_stop(unit: VirtualPutter, driver: PutterDriver, count: int) -> SampleBlock:
    driver.start_stream()
    rows = driver.wait_samples(count, timeout=5.0)
    unit.faults.corrupt_rate = unit.faults.drop_rate = 0.0
    driver.stop_stream()
    time.sleep(0.05)
    return SampleBlock.concat((rows, driver.drain()))


def test_corrupted_bytes_are_counted_and_never_give_a_wrong_sample(
    unit: VirtualPutter, driver: PutterDriver
) -> None:
    unit.faults.corrupt_rate = 0.05
    rows = stream_then_stop(unit, driver, 4000)
    stats = driver.stats
    assert stats.crc_errors + stats.bad_headers > 50
    assert stats.resyncs > 50
    # Every corrupted frame is refused: it shows as a lost sample, never as a bad value.
    assert np.all(np.diff(rows.seq) >= 1)
    assert stats.samples == len(rows)
    assert stats.lost_samples == rows.seq[-1] + 1 - len(rows)
    assert np.abs(rows.accel - static_reading(unit, "face_up")).max() < 8


def test_dropped_samples_show_as_sequence_gaps(unit: VirtualPutter, driver: PutterDriver) -> None:
    unit.faults.drop_rate = 0.05
    rows = stream_then_stop(unit, driver, 4000)
    stats = driver.stats
    assert stats.lost_samples == rows.seq[-1] + 1 - len(rows) > 100
    assert stats.gaps > 100
    assert stats.crc_errors == stats.resyncs == 0
    assert 0.03 < stats.loss_fraction < 0.07


def test_waiting_for_samples_that_do_not_come_times_out(driver: PutterDriver) -> None:
    with pytest.raises(DeviceTimeoutError, match=r"0 of 10 samples after 0\.2 s"):
        driver.wait_samples(10, timeout=0.2)


def test_opening_a_missing_port_is_a_disconnection() -> None:
    with pytest.raises(DeviceDisconnectedError, match="cannot open putter port /nonexistent"):
        PutterDriver.open("/nonexistent/ttyUSB9")


# -- on pyserial's loop:// port: the test writes what a unit would send -----------------


def test_a_reply_of_the_wrong_kind_is_a_protocol_error() -> None:
    # loop:// sends back what is written: IDENTIFY comes back instead of IDENTITY.
    with (
        PutterDriver(serial.serial_for_url("loop://", timeout=0.01), reply_timeout=0.3) as drv,
        pytest.raises(ProtocolError, match="answered IDENTIFY with IDENTIFY, expected IDENTITY"),
    ):
        drv.identify()


def test_sequence_numbers_unwrap_past_65535_and_gaps_are_counted() -> None:
    sent = [*range(65530, 65536), *range(0, 3), *range(5, 10)]
    port = serial.serial_for_url("loop://", timeout=0.01)
    with PutterDriver(port) as drv:
        port.write(b"".join(encode_sample(s, (1, 2, 3), (0, 0, 0), 2500) for s in sent))
        rows = drv.wait_samples(len(sent), timeout=2.0)
        stats = drv.stats
    expected = [s + 65536 if s < 100 else s for s in sent]
    np.testing.assert_array_equal(rows.seq, expected)
    assert (stats.lost_samples, stats.gaps) == (2, 1)


def test_the_putter_answers_unknown_and_malformed_commands_with_an_error(
    unit: VirtualPutter,
) -> None:
    assert unit.url is not None
    with serial.serial_for_url(unit.url, timeout=1.0) as port:
        port.write(encode_frame(0x1E, b""))
        unknown = port.read(8 + len("unknown command 0x1e"))
        port.write(encode_frame(FrameType.SET_RATE, b"\x01"))
        short = port.read(8 + len("payload of 1 B"))
    assert unknown[2:6] == bytes((FrameType.ERROR, 22, 0x1E, 1))
    assert unknown[6:-2] == b"unknown command 0x1e"
    assert short[2:6] == bytes((FrameType.ERROR, 16, FrameType.SET_RATE, 2))


def test_a_unit_speaking_another_protocol_version_is_refused() -> None:
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def firmware_v2() -> None:
        connection, _ = server.accept()
        with connection:
            connection.recv(64)
            reply = Identity("PT000099", "2.0.0", "KXM52-1050", protocol_version=2).encode()
            connection.sendall(encode_frame(FrameType.IDENTITY, reply))
            connection.recv(64)

    unit = threading.Thread(target=firmware_v2)
    unit.start()
    try:
        with (
            PutterDriver.open(f"socket://127.0.0.1:{port}") as drv,
            pytest.raises(
                ProtocolError, match="speaks protocol version 2; this station speaks version 1"
            ),
        ):
            drv.identify()
    finally:
        unit.join(timeout=5)
        server.close()


def test_the_calibrated_stream_is_limited_to_what_the_baud_rate_carries(
    driver: PutterDriver,
) -> None:
    driver.set_rate(1000)
    with pytest.raises(DeviceRejectedError, match="START_STREAM: BAD_VALUE: rate too high"):
        driver.start_stream(calibrated=True)
    driver.set_rate(800)
    driver.start_stream(calibrated=True)
    with pytest.raises(DeviceRejectedError, match="SET_RATE: BAD_VALUE: rate too high"):
        driver.set_rate(801)


def test_an_undrained_buffer_keeps_the_newest_samples_and_counts_the_overrun() -> None:
    port = serial.serial_for_url("loop://", timeout=0.01)
    with PutterDriver(port, buffer_rows=50) as drv:
        port.write(b"".join(encode_sample(s, (1, 2, 3), (0, 0, 0), 0) for s in range(120)))
        deadline = time.monotonic() + 30.0  # a safety net only
        while drv.stats.samples < 120 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert drv.pending() == 50
        rows = drv.drain()
        assert drv.stats.buffer_overruns == 70
    np.testing.assert_array_equal(rows.seq, np.arange(70, 120))


@settings(max_examples=examples(40), deadline=None)
@given(
    start=st.integers(0, 0xFFFF),
    steps=st.lists(st.integers(1, 40), min_size=1, max_size=60),
)
def test_any_run_of_sequence_numbers_unwraps_and_counts_its_losses(
    start: int, steps: list[int]
) -> None:
    counts = np.cumsum([0, *steps]) + start
    port = serial.serial_for_url("loop://", timeout=0.01)
    with PutterDriver(port) as drv:
        port.write(b"".join(encode_sample(int(c), (1, 2, 3), (0, 0, 0), 0) for c in counts))
        rows = drv.wait_samples(len(counts), timeout=2.0)
        stats = drv.stats
    np.testing.assert_array_equal(rows.seq, counts)
    assert stats.lost_samples == sum(steps) - len(steps)
    assert stats.gaps == sum(1 for s in steps if s > 1)
