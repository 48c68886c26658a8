"""Throughput of the serial frame parser on one core.

Parses a recorded-like stream of SAMPLE frames fed in reads of a given size, as the
driver's reader thread does, then decodes the samples into the N-by-8 block. Target:
at least 50 times the device's sample rate (500 samples/s, so 25,000 samples/s).

Run: python benchmarks/bench_parser.py
"""

import random
import time

from station.device.protocol import (
    FrameParser,
    FrameType,
    decode_samples,
    encode_sample,
)
from station.domain.constants import DEFAULT_RATE_HZ, MAX_RATE_HZ

SAMPLES = 200_000
REPEATS = 3


def make_stream(corrupt_fraction: float, rng: random.Random) -> bytes:
    frames = []
    for seq in range(SAMPLES):
        frame = bytearray(
            encode_sample(seq, (2048 + seq % 7, 1230, 2890), (seq % 50 - 25, 3, -4), 2500)
        )
        if rng.random() < corrupt_fraction:
            bit = rng.randrange(len(frame) * 8)
            frame[bit // 8] ^= 1 << (bit % 8)
        frames.append(bytes(frame))
    return b"".join(frames)


def run(stream: bytes, read_size: int) -> tuple[float, int]:
    best = float("inf")
    accepted = 0
    for _ in range(REPEATS):
        parser = FrameParser()
        start = time.perf_counter()
        payloads: list[bytes] = []
        for i in range(0, len(stream), read_size):
            frames = parser.feed(stream[i : i + read_size])
            payloads += [f.payload for f in frames if f.type == FrameType.SAMPLE]
        decode_samples(payloads)
        best = min(best, time.perf_counter() - start)
        accepted = len(payloads)
    return best, accepted


def main() -> None:
    rng = random.Random(1)
    print(f"{SAMPLES} SAMPLE frames (22 bytes each), best of {REPEATS}, one core")
    header = (
        f"{'read size':>9} | {'corrupted':>9} | {'accepted':>8} | {'samples/s':>10} | "
        f"{'x 500 Hz':>8} | {'x 1000 Hz':>9}"
    )
    print(header)
    print("-" * len(header))
    for corrupt in (0.0, 0.01):
        stream = make_stream(corrupt, rng)
        for read_size in (64, 512, 4096):
            seconds, accepted = run(stream, read_size)
            rate = accepted / seconds
            print(
                f"{read_size:>9} | {corrupt:>9.0%} | {accepted:>8} | {rate:>10,.0f} | "
                f"{rate / DEFAULT_RATE_HZ:>8,.0f} | {rate / MAX_RATE_HZ:>9,.0f}"
            )


if __name__ == "__main__":
    main()
