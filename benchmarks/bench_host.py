#!/usr/bin/env python3
"""Measures the host receive path (decode, console model, log); the simulated swarms' speed is
benchmarks/bench_world_swarms.py's."""

from __future__ import annotations

import argparse
import queue
import statistics
import tempfile
import threading
import time
from pathlib import Path
from typing import Self

from particlebot.logs.jsonl import JsonlWriter
from particlebot.protocol import DEFINITION_HASH, Status, encode_frame
from particlebot.radio import Packet, Radio, RadioUrl
from particlebot.session import Listener, ReceivedFrame, Session
from particlebot.swarm.tracker import SwarmTracker

LINK_BYTES_PER_S = 9600 / 10  # 8N1
STATUS_FRAME_BYTES = Status.PAYLOAD_SIZE + 8


class _QueueRadio(Radio):
    def __init__(self) -> None:
        super().__init__("bench://")
        self.packets: queue.Queue[Packet] = queue.Queue()

    @classmethod
    def from_url(cls, url: RadioUrl) -> Self:
        raise NotImplementedError

    def send(self, data: bytes) -> None:
        pass

    def receive(self, timeout: float | None = None) -> Packet | None:
        try:
            return self.packets.get(timeout=timeout)
        except queue.Empty:
            return None


class _Counter(Listener):
    def __init__(self, target: int) -> None:
        self.count = 0
        self.target = target
        self.done_at = 0.0
        self.done = threading.Event()

    def on_frame(self, received: ReceivedFrame) -> None:
        self.count += 1
        if self.count == self.target:
            self.done_at = time.perf_counter()
            self.done.set()


def status_packets(count: int, senders: int = 10) -> list[Packet]:
    packets = []
    for seq in range(count):
        sender = 1 + seq % senders
        status = Status(
            state=3, method=3, run_id=1, s_n=sender, group_size=senders, sensor_faults=0,
            intensity=900 - sender, sensors=(900,) * 6, cycle_phase=seq % 1000, radius_um=90000,
            uptime_ms=seq * 200, definition_hash=DEFINITION_HASH, rx_frames=seq, rx_bad_crc=0,
            rx_bad_length=0, rx_skipped_bytes=0, resets=1, last_reset_cause=1, servo_pulse_us=1400,
        )  # fmt: skip
        data = encode_frame(status, sender, seq & 0xFF)
        packets.append(Packet(data, f"radio-{sender}", 1000.0 + seq * 0.001))
    return packets


def receive_path(count: int, log_dir: Path) -> float:
    """Frames per second through Session -> SwarmTracker + JsonlWriter (flushed per line)."""
    radio = _QueueRadio()
    counter = _Counter(count)
    writer = JsonlWriter(log_dir / "bench.jsonl", radio=radio.url)
    session = Session(radio, [counter, writer])
    session.add_listener(SwarmTracker(session, radio.now))
    packets = status_packets(count)
    with session:
        start = time.perf_counter()
        for packet in packets:
            radio.packets.put(packet)
        if not counter.done.wait(timeout=120):
            raise RuntimeError(f"only {counter.count} of {count} frames came through")
    return count / (counter.done_at - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--frames", type=int, default=20000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    ceiling = LINK_BYTES_PER_S / STATUS_FRAME_BYTES
    with tempfile.TemporaryDirectory() as tmp:
        rates = [receive_path(args.frames, Path(tmp)) for _ in range(args.repeats)]
    rate = statistics.median(rates)
    print(
        f"host receive path (decode + console model + JSONL log, flushed per line): "
        f"{rate:,.0f} STATUS frames/s; a 9600-baud link carries at most {ceiling:.1f} "
        f"({rate / ceiling:,.0f}x headroom)"
    )


if __name__ == "__main__":
    main()
