#!/usr/bin/env python3
"""Measures how many STATUS frames per second the host's StreamDecoder reassembles and decodes."""

from __future__ import annotations

import argparse
import random
import sys
import time

from particlebot.protocol import (
    DEFINITION_HASH,
    Status,
    StreamDecoder,
    encode_frame,
)

# 9600 baud 8N1 carries 960 bytes/s; a STATUS frame is 54 bytes.
LINK_CEILING_FRAMES_PER_S = 960 / (Status.PAYLOAD_SIZE + 8)


def status_stream(count: int, seed: int) -> bytes:
    rng = random.Random(seed)
    frames = []
    for seq in range(count):
        status = Status(
            state=3,
            method=3,
            run_id=1,
            s_n=rng.randrange(1, 10),
            group_size=9,
            sensor_faults=0,
            intensity=rng.randrange(1024),
            sensors=tuple(rng.randrange(1024) for _ in range(6)),
            cycle_phase=rng.randrange(1000),
            radius_um=rng.randrange(77500, 117501),
            uptime_ms=seq * 2000,
            definition_hash=DEFINITION_HASH,
            rx_frames=seq,
            rx_bad_crc=0,
            rx_bad_length=0,
            rx_skipped_bytes=0,
            resets=1,
            last_reset_cause=1,
            servo_pulse_us=1400,
        )
        frames.append(encode_frame(status, rng.randrange(1, 254), seq & 0xFF))
    return b"".join(frames)


def measure(stream: bytes, chunk: int, decode_messages: bool) -> tuple[int, float]:
    decoder = StreamDecoder()
    start = time.perf_counter()
    frames = 0
    for offset in range(0, len(stream), chunk):
        for frame in decoder.feed(stream[offset : offset + chunk], "radio"):
            frames += 1
            if decode_messages and frame.message is None:
                raise AssertionError("undecodable STATUS")
    return frames, time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--frames", type=int, default=50_000)
    parser.add_argument("--repeat", type=int, default=3, help="best of this many runs")
    args = parser.parse_args()
    stream = status_stream(args.frames, seed=1)
    print(f"link ceiling at 9600 baud: {LINK_CEILING_FRAMES_PER_S:.1f} STATUS frames/s")
    # 64 bytes: a typical serial read; 1 byte: the worst case; 4096: a log file replay.
    for chunk in (1, 64, 4096):
        for decode_messages in (False, True):
            best = min(measure(stream, chunk, decode_messages)[1] for _ in range(args.repeat))
            rate = args.frames / best
            what = "frames + Status objects" if decode_messages else "frames"
            print(
                f"chunks of {chunk:4d} B, {what:23s}: {rate:11,.0f} frames/s"
                f" ({rate / LINK_CEILING_FRAMES_PER_S:,.0f}x the link)"
            )
    return 0


if __name__ == "__main__":
    sys.exit(main())
