"""The reader's pacing and the station's own reads: at the putter's rate the reader rests
and the station's pass reads the port itself; the reader reads at once while someone waits
on the port, on a stream faster than the putter's own, and when nobody read for a while."""

import contextlib
import itertools
import os
import queue
import threading
import time
from collections.abc import Callable, Iterator

import numpy as np
import pytest
import serial
from hypothesis import given
from hypothesis import strategies as st

from station.device import DeviceDisconnectedError, ProtocolError, PutterDriver
from station.device import link as link_module
from station.device.link import PutterLink
from station.device.ports import open_port
from station.device.protocol import Frame, FrameType, encode_frame, encode_sample
from station.simulator import VirtualPutter

#: Longer than any test may take: a reader resting this long has not been woken.
FOREVER_S = 3600.0
#: Safety net for a join or a wait, not a speed requirement.
JOIN_S = 60.0


def samples(first: int, count: int) -> bytes:
    return b"".join(
        encode_sample(i, (2048, 2048, 2867), (0, 0, 0), 2500) for i in range(first, first + count)
    )


def feed_in_thread(link: PutterLink, data: bytes) -> threading.Thread:
    thread = threading.Thread(target=link.data_received, args=(data,), daemon=True)
    thread.start()
    return thread


def until(condition: Callable[[], bool]) -> None:
    deadline = time.monotonic() + JOIN_S
    while not condition():
        assert time.monotonic() < deadline, "hung"
        time.sleep(0.005)


@pytest.fixture
def resting_forever(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(link_module, "REST_S", FOREVER_S)


@pytest.fixture
def pty_port() -> Iterator[tuple[int, serial.Serial]]:
    """A real pty: its master's fd (the putter's end) and the station's port on it."""
    master, slave = os.openpty()
    port = open_port(os.ttyname(slave), baudrate=115200, timeout=0.01)
    assert isinstance(port, serial.Serial)
    try:
        yield master, port
    finally:
        port.close()
        with contextlib.suppress(OSError):  # a test may have pulled the cable
            os.close(master)
        os.close(slave)


def resting(link: PutterLink, first_chunk: bytes) -> threading.Thread:
    """A reader thread that read ``first_chunk`` and now rests."""
    reader = feed_in_thread(link, first_chunk)
    until(lambda: link._resting)
    return reader


@pytest.mark.usefixtures("resting_forever")
def test_a_small_chunk_rests_the_reader_until_someone_waits_on_the_port() -> None:
    link = PutterLink("pty", 1024)
    reader = resting(link, samples(0, 1))
    assert len(link.raw) == 1  # what it read goes in before it rests
    reader.join(0.1)
    assert reader.is_alive()
    with link.attended():  # a command was sent
        reader.join(JOIN_S)
        assert not reader.is_alive()


@pytest.mark.usefixtures("resting_forever")
def test_closing_the_link_ends_the_readers_rest() -> None:
    link = PutterLink("pty", 1024)
    reader = resting(link, samples(0, 1))
    link.close()
    reader.join(JOIN_S)
    assert not reader.is_alive()


@pytest.mark.usefixtures("resting_forever")
def test_a_reply_awaited_or_a_big_chunk_never_rests_the_reader() -> None:
    link = PutterLink("pty", 4096)
    with link.attended():
        reply = encode_frame(FrameType.ACK, bytes([FrameType.START_STREAM]))
        feed_in_thread(link, reply).join(JOIN_S)
    assert link.replies.qsize() == 1
    big = samples(0, link_module.PACE_BELOW_BYTES // 20 + 1)
    reader = feed_in_thread(link, big)
    reader.join(JOIN_S)
    assert not reader.is_alive()


@pytest.mark.usefixtures("resting_forever")
def test_a_stream_faster_than_the_putters_own_is_read_unpaced() -> None:
    link = PutterLink("pty", 1 << 16)
    chunk = samples(0, 50)
    assert len(chunk) < link_module.PACE_BELOW_BYTES  # small: a paced reader rests after it
    with link.attended():  # keeps the reader from resting while the rate is measured
        # 1 kB a call, back to back, until the link has judged a window of them unpaced
        # (above 30 kB/s unless the calls took 33 ms each: a window the machine stalled
        # is judged again on the next). Waiting on the link's own judgement, not on the
        # clock: a worker descheduled for the whole window judged nothing before.
        deadline = time.monotonic() + JOIN_S
        while link._paced:
            assert time.monotonic() < deadline, "the stream was never judged unpaced"
            link.data_received(chunk)
    reader = feed_in_thread(link, chunk)
    reader.join(JOIN_S)
    assert not reader.is_alive()


@pytest.mark.usefixtures("resting_forever")
def test_the_station_reads_what_the_port_holds_while_the_reader_rests(
    pty_port: tuple[int, serial.Serial],
) -> None:
    master, port = pty_port
    link = PutterLink("pty", 4096)
    reader = resting(link, samples(0, 1))
    sent = samples(1, 100)
    os.write(master, sent)
    until(lambda: port.in_waiting == len(sent))
    link.read_now(port)
    block = link.raw.drain()
    assert block.seq.tolist() == list(range(101))
    assert port.in_waiting == 0
    reader.join(0.1)
    assert reader.is_alive()  # its rest goes on: the station reads the port
    link.close()
    reader.join(JOIN_S)


def test_the_station_leaves_the_port_to_a_reader_that_is_not_resting(
    pty_port: tuple[int, serial.Serial],
) -> None:
    master, port = pty_port
    link = PutterLink("pty", 4096)
    sent = samples(0, 10)
    os.write(master, sent)
    until(lambda: port.in_waiting == len(sent))
    link.read_now(port)
    assert len(link.raw) == 0
    assert port.in_waiting == len(sent)


def test_a_reader_nobody_relieves_reads_again_after_its_rest(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(link_module, "REST_S", 0.05)
    link = PutterLink("pty", 1024)
    reader = feed_in_thread(link, samples(0, 1))
    reader.join(JOIN_S)
    assert not reader.is_alive()


def test_a_failing_port_ends_the_readers_rest(
    pty_port: tuple[int, serial.Serial], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(link_module, "REST_S", FOREVER_S)
    master, port = pty_port
    link = PutterLink("pty", 1024)
    reader = resting(link, samples(0, 1))
    os.close(master)  # the cable pulled: the port's in_waiting now fails
    link.read_now(port)
    reader.join(JOIN_S)
    assert not reader.is_alive()  # its own read meets the failure (a ReaderThread ends the link)


@pytest.mark.usefixtures("resting_forever")
def test_at_the_putters_own_rate_the_stations_drains_parse_the_stream() -> None:
    """The reader parses its first chunk and rests; every later sample is parsed by the
    station's drains, in order and none lost."""
    parsed_by_reader: list[int] = []
    received = PutterLink.data_received

    def counting(self: PutterLink, data: bytes) -> None:
        parsed_by_reader.append(len(data))
        received(self, data)

    monkeypatch = pytest.MonkeyPatch()
    monkeypatch.setattr(PutterLink, "data_received", counting)
    try:
        with VirtualPutter(seed=3, serial="PT000001", speed=1.0) as putter:
            url = putter.serve_pty()
            with PutterDriver.open(url) as driver:
                driver.start_stream()
                until(lambda: driver._link._resting)
                reads = len(parsed_by_reader)
                got: list[np.ndarray] = []

                def drained_600() -> bool:
                    got.append(driver.drain().seq)
                    return sum(map(len, got)) >= 600

                until(drained_600)
                assert len(parsed_by_reader) == reads  # the reader still rests
                seq = np.concatenate(got)
                assert np.array_equal(seq, np.arange(seq[0], seq[0] + len(seq)))
    finally:
        monkeypatch.undo()


def test_a_socket_whose_peer_went_away_is_noticed_while_the_station_drains() -> None:
    """A socket's ``in_waiting`` holds 0 and raises nothing once the peer is gone: the
    station's reads, finding nothing, leave the reader's rest to run out, and its own read
    meets the end of the stream."""
    with VirtualPutter(seed=3, serial="PT000001", speed=1.0) as putter:
        url = putter.serve_socket()
        with PutterDriver.open(url) as driver:
            driver.start_stream()
            until(lambda: driver._link._resting)
            putter.unplug()
            with pytest.raises(DeviceDisconnectedError):
                drain_until_it_fails(driver)


def drain_until_it_fails(driver: PutterDriver) -> None:
    """Drain as the station's passes do, until the driver raises (or the hang guard)."""
    deadline = time.monotonic() + JOIN_S
    while time.monotonic() < deadline:
        driver.drain()
        time.sleep(0.05)


@pytest.mark.usefixtures("resting_forever")
def test_a_bug_in_the_stations_read_fails_the_link_and_wakes_the_reader(
    pty_port: tuple[int, serial.Serial], monkeypatch: pytest.MonkeyPatch
) -> None:
    master, port = pty_port
    link = PutterLink("pty", 1024)
    reader = resting(link, samples(0, 1))

    def broken(data: bytes) -> None:
        raise RuntimeError("a parser bug")

    monkeypatch.setattr(link, "_received", broken)
    os.write(master, samples(1, 5))
    until(lambda: port.in_waiting > 0)
    link.read_now(port)
    assert isinstance(link.failure, ProtocolError)
    reader.join(JOIN_S)
    assert not reader.is_alive()


def test_a_reply_is_handed_over_once_the_samples_read_before_it_are_stored() -> None:
    """Whoever a reply wakes (``stop_stream`` waiting for its ACK, then a drain or a
    restart of the sequence) finds every sample that came before it stored already."""
    link = PutterLink("test", 1024)
    stored_at_reply: list[int] = []

    class Witness(queue.Queue[Frame]):
        def put(self, item: Frame, block: bool = True, timeout: float | None = None) -> None:
            stored_at_reply.append(link.stats().samples)
            super().put(item, block, timeout)

    link.replies = Witness()
    with link.attended():  # a command waits for its reply: the reader does not rest
        link.data_received(samples(0, 5) + encode_frame(FrameType.ACK, b"\x00"))
    assert stored_at_reply == [5]
    assert link.replies.get_nowait().type == FrameType.ACK


def _stream(first: int, count: int, x: int) -> bytes:
    return b"".join(
        encode_sample(i % 65536, (x, 2048, 2867), (0, 0, 0), 2500)
        for i in range(first, first + count)
    )


@given(
    held=st.integers(0, 20),
    late=st.integers(0, 40),
    other_ack=st.booleans(),
    fresh=st.integers(0, 40),
    cuts=st.lists(st.integers(0, 2000), max_size=6),
)
def test_a_fresh_stream_hands_out_only_what_the_unit_sent_after_its_start_was_acknowledged(
    held: int, late: int, other_ack: bool, fresh: int, cuts: list[int]
) -> None:
    """Samples of an earlier stream (at the rail, 4095) held undrained when the stream is
    restarted, or still arriving before the unit acknowledges START_STREAM (an ACK of
    another command ends nothing), never come out; the new stream's do, from 0, however
    the port cuts the bytes into chunks."""
    link = PutterLink("test", 1024)
    with link.attended():  # a command waits for its reply: the reader does not rest
        link.data_received(_stream(1000, held, 4095))
        link.restart_stream()
        wire = _stream(1000 + held, late, 4095)
        if other_ack:
            wire += encode_frame(FrameType.ACK, bytes((FrameType.SET_RATE,)))
        wire += encode_frame(FrameType.ACK, bytes((FrameType.START_STREAM,)))
        wire += _stream(0, fresh, 2048)
        bounds = sorted({0, len(wire), *(c for c in cuts if c < len(wire))})
        for start, end in itertools.pairwise(bounds):
            link.data_received(wire[start:end])
    rows = link.raw.drain()
    np.testing.assert_array_equal(rows.seq, np.arange(fresh))
    assert (rows.accel[:, 0] == 2048).all()
    assert link.stats().lost_samples == 0
    acked = [link.replies.get_nowait().payload[0] for _ in range(link.replies.qsize())]
    assert acked == [*([FrameType.SET_RATE] if other_ack else []), FrameType.START_STREAM]
