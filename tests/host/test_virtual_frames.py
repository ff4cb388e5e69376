"""A noise-free virtual swarm delivers every frame whole: one frame per RF packet, no bad frame."""

from __future__ import annotations

from particlebot.console.model import Campaign, ConsoleModel
from particlebot.protocol import FRAME_OVERHEAD, SYNC, Method
from particlebot.radio import open_radio
from particlebot.radio.virtual import VirtualRadio
from particlebot.session import Session
from tests.host.fakes import wait_until


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


def finished(model: ConsoleModel, campaign: Campaign) -> bool:
    """Waits (on the wall clock; the swarm runs as fast as it can) until campaign has ended."""

    def done() -> bool:
        model.poll()
        return campaign.done

    return wait_until(done, timeout=30)


def test_start_stop_cycles_on_a_quiet_virtual_air_lose_no_frame() -> None:
    # What a person did in the console: START, wait for the wave, STOP; four times. Particles
    # then send INTENSITY, periodic STATUS and answers to the console's PINGs close together.
    radio = open_radio("virtual://10?speed=max&kinematics=0")
    assert isinstance(radio, VirtualRadio)
    base_node = 0  # the base station's radio is the first node on the air
    packets: list[tuple[int, bytes]] = []

    def record(source: int, receiver: int, data: bytes) -> bool:
        if receiver == base_node:
            packets.append((source, data))
        return False  # nothing is lost: this only watches the air

    radio.swarm.air.drop = record
    session = Session(radio)
    model = ConsoleModel(session, radio.now)
    session.add_listener(model)
    with session:
        assert wait_until(lambda: len(model.rows()) == 10, timeout=20)
        for _ in range(4):
            start = model.start(Method.COUNTING, cycle_steps=75)
            assert finished(model, start) and start.success, start.outcome
            stop = model.stop()
            assert finished(model, stop) and stop.success, stop.outcome
    particle_packets = [data for source, data in packets if source != base_node]
    assert len(particle_packets) > 200
    not_one_frame = [data.hex() for data in particle_packets if len(frame_lengths(data) or []) != 1]
    assert not_one_frame == []
    bad = {reason: model.drops.get(reason, 0) for reason in ("bad_crc", "bad_length", "truncated")}
    assert bad == {"bad_crc": 0, "bad_length": 0, "truncated": 0}
    assert model.drops.get("skipped", 0) == 0
