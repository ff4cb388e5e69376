"""Native particles on the swarm's clock: bytes from the radio reach the logic at the first tick
after each is in, never before, and frames leave one at a time with the firmware's quiet gap."""

from __future__ import annotations

import itertools

import pytest

from particlebot.firmware.native import firmware_constants
from particlebot.protocol import BASE_STATION_ID, Ping, encode_frame
from particlebot.sim.air.medium import AirPacket, Reception, char_cycles
from particlebot.sim.clock import CYCLES_PER_MS
from particlebot.sim.particles.native import NativeParticles, native_factory
from particlebot.sim.particles.native.particles import TICK_CYCLES, FirmwareParticle
from tests.sim.particles.native.delegate import Delegate


class Recording(Delegate):
    """The firmware logic, noting when each byte reached it."""

    def __init__(self, inner: FirmwareParticle) -> None:
        super().__init__(inner)
        self.now_ms = 0
        self.got: list[tuple[int, int]] = []  # (ms, byte)

    def receive(self, data: bytes) -> None:
        self.got += [(self.now_ms, b) for b in data]
        super().receive(data)

    def tick(self, now_ms: int) -> None:
        self.now_ms = now_ms
        super().tick(now_ms)


@pytest.mark.parametrize("line_start", [0, 123_456 * 9600, 7_777_777 * 9600 + 5000])
def test_each_byte_reaches_the_logic_at_the_first_tick_after_it_is_in(line_start: int) -> None:
    recorders: list[Recording] = []

    def factory(image: bytes, seed: int) -> FirmwareParticle:
        recorders.append(Recording(native_factory(image, seed)))
        return recorders[-1]

    particles = NativeParticles([1], factory=factory)
    data = bytes(range(40))
    packet = AirPacket(0, -1, data, 0, 0, 0)
    copy = Reception(packet, 0, line_start // 9600, False, False, line_start, 9600)
    particles.receive(copy)
    particles.run_until(copy.last + 2 * TICK_CYCLES)
    got = recorders[0].got
    assert bytes(b for _, b in got) == data
    for i, (ms, _) in enumerate(got):
        due = copy.byte_end(i)
        assert due <= ms * CYCLES_PER_MS < due + TICK_CYCLES, i
    particles.close()


def test_frames_leave_one_at_a_time_with_the_quiet_gap_after_each() -> None:
    particles = NativeParticles([7])
    particles.run_until(200 * CYCLES_PER_MS)
    ping = encode_frame(Ping(target=255), BASE_STATION_ID, 1)
    packet = AirPacket(0, -1, ping, 0, 0, 0)
    at = 200 * CYCLES_PER_MS * 9600
    particles.receive(Reception(packet, 0, at // 9600, False, False, at, 9600))
    sent = particles.run_until(5000 * CYCLES_PER_MS)
    times = [b.cycle for b in sent]
    assert times == sorted(times) and len(sent) >= 2 * 54  # the answer and a periodic STATUS
    gaps = [b - a for a, b in itertools.pairwise(times)]
    char = char_cycles()
    quiet = [g for g in gaps if g > 2 * char]
    assert quiet and min(quiet) >= firmware_constants().inter_frame_gap_ms * CYCLES_PER_MS
    particles.close()
