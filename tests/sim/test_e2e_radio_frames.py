"""The real firmware on emulated XBees: one frame per RF packet, and PING replies spread out."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from particlebot.protocol import (
    BROADCAST_ID,
    GetParam,
    Intensity,
    Param,
    ParamValue,
    Ping,
    Status,
    StreamDecoder,
    encode_frame,
)
from particlebot.sim.air.medium import BASE
from particlebot.sim.clock import CPU_HZ
from particlebot.sim.swarm import Level, SimSwarm, SwarmConfig
from particlebot.sim.swarm.base import BaseStation

pytestmark = [pytest.mark.usefixtures("built_images"), pytest.mark.e2e]

SLOT_S = 0.060
"""A broadcast PING is answered in a random one of these slots (a STATUS takes 56 ms at 9600)."""
SLOTS_WITHOUT_GROUP = 10
# Periodic STATUS frames would mix with the answers being timed: push them out of the way.
QUIET = {Param.STATUS_PERIOD_MS: 60000}


def whole_frames(data: bytes) -> list[bytes]:
    """The frames data holds, each as sent; fails unless data is nothing but whole frames."""
    decoder = StreamDecoder()
    frames = [frame.raw for frame in decoder.feed(data)]
    frames += [frame.raw for frame in decoder.flush()]
    assert b"".join(frames) == data, f"{data.hex()} is not made of whole frames"
    return frames


@pytest.fixture
def trio() -> Iterator[SimSwarm]:
    with SimSwarm(SwarmConfig(level=Level.EMULATED, count=3, params=QUIET)) as swarm:
        yield swarm


def test_back_to_back_replies_leave_as_one_rf_packet_per_frame(trio: SimSwarm) -> None:
    """Two STATUS frames and a PARAM_VALUE queued at once (104 B and more: past one RF payload)
    go out one frame per packet, so a foreign packet landing between them at every receiver
    corrupts nothing."""
    swarm = trio
    base = BaseStation(swarm)
    swarm.run_for(0.5)
    talker = swarm.ids[0]
    asked = base.send(Ping(target=talker))
    base.send(Ping(target=talker))
    base.send(GetParam(target=talker, param=Param.ROUND_MS))

    def talker_on_air() -> bool:
        return any(p.source == 0 and p.aired / CPU_HZ >= asked for p in swarm.air.packets)

    assert swarm.run_until_true(talker_on_air, 0.5, check_every_s=0.001)
    # A foreign frame put on the air now reaches every radio right after the talker's first
    # packet, before anything the talker sends later.
    foreign = encode_frame(Intensity(run_id=99, round=0, repeat=0, intensity=5), 200, 0)
    swarm.inject(foreign)
    swarm.run_for(0.5)

    packets = [p for p in swarm.air.packets if p.source == 0 and p.aired / CPU_HZ >= asked]
    assert all(len(whole_frames(p.data)) == 1 for p in packets)
    assert len(packets) >= 3
    replies = [type(m) for heard, m in base.frames(since_s=asked) if heard.source == 0]
    assert replies.count(Status) >= 2 and ParamValue in replies
    # Each listener got the talker's three frames and the foreign one whole, and its own parser
    # counted no damage.
    for index in (1, 2):
        frames, stats = swarm.received(index)
        from_talker = [type(f.message) for t, f in frames if f.sender == talker and t >= asked]
        assert from_talker == replies
        assert any(f.raw == foreign for _, f in frames)
        assert (stats.bad_crc, stats.bad_length, stats.skipped_bytes) == (0, 0, 0)
        status = _status_of(base, swarm.ids[index])
        assert (status.rx_bad_crc, status.rx_bad_length, status.rx_skipped_bytes) == (0, 0, 0)


def _status_of(base: BaseStation, particle_id: int) -> Status:
    asked = base.send(Ping(target=particle_id))
    assert base.swarm.run_until_true(lambda: particle_id in base.statuses(asked), 0.5)
    return base.statuses(asked)[particle_id]


def test_broadcast_ping_answers_spread_over_slots_and_fit_the_base_radio() -> None:
    """Eight particles asked at once answer in random 60 ms slots (of 10 while no group is
    known), all within 0.6 s, and the base station's radio buffer never overflows; a PING to one
    id is answered at once."""
    count = 8
    with SimSwarm(SwarmConfig(level=Level.EMULATED, count=count, params=QUIET)) as swarm:
        base = BaseStation(swarm)
        swarm.run_for(0.5)
        asked = base.send(Ping(target=BROADCAST_ID))
        ping = base.sent[-1][1]
        swarm.run_for(1.0)

        delays = []
        for index, particle_id in enumerate(swarm.ids):
            copy = next(
                r
                for r in swarm.air.receptions
                if r.receiver == index and r.packet.source == BASE and r.packet.data == ping
            )
            received = copy.last
            sent = [b for b in swarm.emulated.sims[index].uart if b.cycle > received]
            assert sent, f"particle {particle_id} did not answer"
            delay = (sent[0].cycle - received) / CPU_HZ
            delays.append(delay)
            answers = [h for h, _ in base.frames(Status, asked) if h.frame.sender == particle_id]
            assert len(answers) == 1, f"particle {particle_id}"
        # Whole slots (the particle's clock and main loop add a millisecond or two).
        slots = [round(d / SLOT_S) for d in delays]
        assert all(abs(d - s * SLOT_S) < 0.003 for d, s in zip(delays, slots, strict=True)), delays
        assert all(0 <= s < SLOTS_WITHOUT_GROUP for s in slots), slots
        assert len(set(slots)) >= 4, slots
        to_base = [r for r in swarm.air.receptions if r.receiver == BASE]
        assert not any(r.overflow for r in to_base)
        assert sorted(base.statuses(asked)) == swarm.ids

        # One particle by its id: at once.
        asked = base.send(Ping(target=swarm.ids[3]))
        ping = base.sent[-1][1]
        swarm.run_for(0.3)
        copy = next(
            r
            for r in swarm.air.receptions
            if r.receiver == 3 and r.packet.source == BASE and r.packet.data == ping
        )
        first = next(b for b in swarm.emulated.sims[3].uart if b.cycle > copy.last)
        assert (first.cycle - copy.last) / CPU_HZ < 0.003
        assert list(base.statuses(asked)) == [swarm.ids[3]]
