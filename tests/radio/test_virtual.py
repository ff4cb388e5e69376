"""A noise-free virtual swarm delivers every frame whole: one frame per RF packet, no bad frame."""

from __future__ import annotations

from particlebot.protocol import FRAME_OVERHEAD, SYNC
from particlebot.radio import open_radio
from particlebot.radio.virtual import VirtualRadio
from particlebot.sim.air.medium import BASE, AirPacket
from particlebot.swarm.api import Swarm


def frame_lengths(packet: bytes) -> list[int] | None:
    """The lengths of the whole frames packet consists of, or None if it is anything else."""
    lengths: list[int] = []
    at = 0
    while at < len(packet):
        if packet[at : at + 2] != SYNC or at + 2 >= len(packet):
            return None
        length = packet[at + 2] + FRAME_OVERHEAD
        lengths.append(length)
        at += length
    return lengths if at == len(packet) else None


def test_start_stop_cycles_on_a_quiet_virtual_air_lose_no_frame() -> None:
    # What a person did in the console: START, wait for the wave, STOP; four times. Particles
    # then send INTENSITY, periodic STATUS and answers to the console's PINGs close together.
    radio = open_radio("virtual://10?speed=max&kinematics=0")
    assert isinstance(radio, VirtualRadio)
    packets: list[tuple[int, bytes]] = []

    def record(packet: AirPacket, receiver: int) -> bool:
        if receiver == BASE:
            packets.append((packet.source, packet.data))
        return False  # nothing is lost: this only watches the air

    radio.swarm.air.drop = record
    with Swarm.open(radio, log_dir=None) as swarm:
        swarm.wait_for(count=10, timeout=20)
        for _ in range(4):
            swarm.start("D", cycle_steps=75)
            swarm.sleep(6)
            report = swarm.stop()
            assert report.confirmed, report
        swarm.sleep(3)  # a STATUS from every particle after the last STOP
        drops = dict(swarm.tracker.drops)
        particles = swarm.particles()
    particle_packets = [data for source, data in packets if source != BASE]
    assert len(particle_packets) > 200
    not_one_frame = [data.hex() for data in particle_packets if len(frame_lengths(data) or []) != 1]
    assert not_one_frame == []
    bad = {reason: drops.get(reason, 0) for reason in ("bad_crc", "bad_length", "truncated")}
    assert bad == {"bad_crc": 0, "bad_length": 0, "truncated": 0}
    assert drops.get("skipped", 0) == 0
    # And the particles heard the base station's frames whole too (their BAD RX column).
    particle_bad = {
        p.id: (p.status.rx_bad_crc, p.status.rx_bad_length, p.status.rx_skipped_bytes)
        for p in particles
        if p.status is not None
    }
    assert len(particle_bad) == 10
    assert set(particle_bad.values()) == {(0, 0, 0)}, particle_bad
