"""CPU of one streaming virtual putter's thread, per second of real time.

    python benchmarks/bench_putter_cpu.py                  # 1× and 20×, 10 s each
    python benchmarks/bench_putter_cpu.py --burst-ms 2     # as it was: a wake every 2 ms

A virtual putter serves a pty; this process opens it, sends START_STREAM (raw) as the
station does, and reads everything every 16 ms for ``--seconds``. The figure is the
putter thread's own CPU clock (``pthread_getcpuclockid``) over that time, and the
samples read (a frame is 22 bytes), so that a cheaper setting is seen to lose none.
``--burst-ms`` sets :data:`station.simulator.putter.BURST_S` for the run, to compare
the kept burst interval with another.
"""

import argparse
import os
import time

import station.simulator.putter as putter_module
from station.device.protocol import SAMPLE_DTYPE, FrameType, StreamMode, encode_frame
from station.simulator.putter import VirtualPutter

FRAME_BYTES = len(encode_frame(FrameType.SAMPLE, bytes(SAMPLE_DTYPE.itemsize)))


def measure(speed: float, seconds: float) -> tuple[float, int]:
    """CPU seconds of the putter's thread and samples read, streaming ``seconds``."""
    putter = VirtualPutter(seed=1, speed=speed)
    port = os.open(putter.serve_pty(), os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    thread = putter._thread
    assert thread is not None
    assert thread.ident is not None
    clock = time.pthread_getcpuclockid(thread.ident)
    try:
        os.write(port, encode_frame(FrameType.START_STREAM, bytes([StreamMode.RAW])))
        start = time.clock_gettime(clock)
        received = 0
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            time.sleep(0.016)
            try:
                while chunk := os.read(port, 65536):
                    received += len(chunk)
            except BlockingIOError:
                pass
        return time.clock_gettime(clock) - start, received // FRAME_BYTES
    finally:
        putter.close()
        os.close(port)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speed", type=float, action="append", help="default: 1 and 20")
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--burst-ms", type=float, default=putter_module.BURST_S * 1000)
    args = parser.parse_args()
    putter_module.BURST_S = args.burst_ms / 1000  # type: ignore[misc]
    print(f"virtual putter, a burst every {args.burst_ms:g} ms, {args.seconds:g} s each")
    print("| speed | putter thread CPU | % of a core | samples read |")
    print("|---|---|---|---|")
    for speed in args.speed or [1.0, 20.0]:
        cpu, samples = measure(speed, args.seconds)
        print(
            f"| {speed:g}× | {cpu * 1000:.0f} ms | {100 * cpu / args.seconds:.1f} % | {samples} |"
        )


if __name__ == "__main__":
    main()
