"""The reader's pacing: it rests between small chunks, never while a reply is due nor on
a stream faster than the putter's own (a sped-up simulator)."""

import threading
import time

import pytest

from station.device import link as link_module
from station.device.link import PutterLink
from station.device.protocol import FrameType, encode_frame, encode_sample

#: Longer than any test may take: a reader resting this long has not been woken.
FOREVER_S = 3600.0
#: Safety net for a join, not a speed requirement.
JOIN_S = 60.0


def feed_in_thread(link: PutterLink, data: bytes) -> threading.Thread:
    thread = threading.Thread(target=link.data_received, args=(data,), daemon=True)
    thread.start()
    return thread


@pytest.fixture
def resting_forever(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(link_module, "PACE_S", FOREVER_S)


@pytest.mark.usefixtures("resting_forever")
def test_a_small_chunk_rests_the_reader_until_a_reply_is_due() -> None:
    link = PutterLink("pty", 1024)
    reader = feed_in_thread(link, encode_sample(0, (2048, 2048, 2867), (0, 0, 0), 2500))
    deadline = time.monotonic() + JOIN_S
    while len(link.raw) < 1:  # what it read goes in before it rests
        assert time.monotonic() < deadline
        time.sleep(0.01)
    reader.join(0.1)
    assert reader.is_alive()  # resting
    link.expect_reply(True)  # a command was sent
    reader.join(JOIN_S)
    assert not reader.is_alive()


@pytest.mark.usefixtures("resting_forever")
def test_a_reply_due_or_a_big_chunk_never_rests_the_reader() -> None:
    link = PutterLink("pty", 4096)
    link.expect_reply(True)
    feed_in_thread(link, encode_frame(FrameType.ACK, bytes([FrameType.START_STREAM]))).join(JOIN_S)
    assert link.replies.qsize() == 1
    link.expect_reply(False)
    big = b"".join(
        encode_sample(i, (2048, 2048, 2867), (0, 0, 0), 2500)
        for i in range(link_module.PACE_BELOW_BYTES // 20 + 1)
    )
    reader = feed_in_thread(link, big)
    reader.join(JOIN_S)
    assert not reader.is_alive()


@pytest.mark.usefixtures("resting_forever")
def test_a_stream_faster_than_the_putters_own_is_read_unpaced() -> None:
    link = PutterLink("pty", 1 << 16)
    chunk = b"".join(encode_sample(i, (2048, 2048, 2867), (0, 0, 0), 2500) for i in range(50))
    assert len(chunk) < link_module.PACE_BELOW_BYTES  # small: a paced reader rests after it
    link.expect_reply(True)  # keeps the reader from resting while the rate is measured
    start = time.monotonic()
    # 1 kB a call: far above 30 kB/s however busy the machine, unless calls took 33 ms.
    while time.monotonic() - start <= link_module.RATE_WINDOW_S:
        link.data_received(chunk)
    link.expect_reply(False)
    reader = feed_in_thread(link, chunk)
    reader.join(JOIN_S)
    assert not reader.is_alive()
