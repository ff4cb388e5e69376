"""Garbage and damaged frames on the air: emulated particles survive, count it, and still obey."""

from __future__ import annotations

import random
from collections.abc import Iterator

import pytest

from particlebot.protocol import (
    BASE_STATION_ID,
    BROADCAST_ID,
    Intensity,
    Method,
    Param,
    Ping,
    SetId,
    SetParam,
    Start,
    State,
    Status,
    Stop,
    StreamDecoder,
    encode_frame,
)
from particlebot.sim.air.medium import BASE
from particlebot.sim.clock import CPU_HZ
from particlebot.sim.particles.emulated.servo import missed_frames, period_errors_us
from particlebot.sim.swarm import Level, SimSwarm, SwarmConfig
from particlebot.sim.swarm.base import BaseStation

pytestmark = [pytest.mark.usefixtures("built_images"), pytest.mark.e2e]

COUNT = 5
ROUND_MS = 1000
SPRAY_S = 3.0
SPRAY_EVERY_S = 0.04
# An edge of the pulse waits while another interrupt (Timer0, Serial1) finishes; the longest,
# Serial1's transmit interrupt, takes ~120 cycles (15 us). benchmarks/bench_sim.py saw 14.25 us.
SERVO_JITTER_US = 20


@pytest.fixture
def swarm() -> Iterator[SimSwarm]:
    with SimSwarm(
        SwarmConfig(level=Level.EMULATED, count=COUNT, params={Param.ROUND_MS: ROUND_MS})
    ) as emulated:
        yield emulated


def damaged(rng: random.Random) -> bytes:
    """A real command or reading frame with something broken: bits flipped, cut short, a length
    beyond max_payload, bytes inserted, or a false start before a bad CRC."""
    message = rng.choice(
        [
            Start(
                run_id=9,
                method=Method.COUNTING,
                cycle_steps=50,
                wave_size=0,
                update_interval_s=0,
                phototaxis=0,
            ),
            Stop(),
            SetParam(target=BROADCAST_ID, param=Param.CYCLE_STEPS, value=20),
            SetId(target=1, new_id=77),
            Ping(target=BROADCAST_ID),
            Intensity(run_id=9, round=0, repeat=0, intensity=1000),
        ]
    )
    sender = 3 if isinstance(message, Intensity) else BASE_STATION_ID
    frame = bytearray(encode_frame(message, sender, rng.randrange(256)))
    kind = rng.randrange(5)
    if kind == 0:
        for _ in range(rng.randint(1, 3)):
            frame[rng.randrange(2, len(frame))] ^= 1 << rng.randrange(8)
    elif kind == 1:
        frame = frame[: rng.randrange(3, len(frame) - 1)]
    elif kind == 2:
        frame[2] = rng.randint(49, 255)
    elif kind == 3:
        at = rng.randrange(3, len(frame))
        frame[at:at] = rng.randbytes(rng.randint(1, 4))
    else:  # a false start: a sync marker and a little garbage before a damaged CRC
        frame[-1] ^= 1 << rng.randrange(8)
        frame[0:0] = frame[0:2] + rng.randbytes(rng.randint(0, 3))
    return bytes(frame)


def spray(swarm: SimSwarm, rng: random.Random, seconds: float) -> bytes:
    """Puts random bytes and damaged frames on the air for `seconds` (about half the capacity
    of a 9600-baud link); returns everything sprayed."""
    sprayed = bytearray()
    end = swarm.time_s + seconds
    while swarm.time_s < end:
        chunk = rng.randbytes(rng.randint(5, 40)) if rng.random() < 0.5 else damaged(rng)
        # None of it may be a valid frame by itself (a damaged START would start a run).
        assert StreamDecoder().feed(chunk) == []
        swarm.inject(chunk)
        sprayed += chunk
        swarm.run_for(SPRAY_EVERY_S)
    return bytes(sprayed)


def status_after_quiet_ping(base: BaseStation, index: int) -> tuple[Status, float]:
    """A STATUS asked of one particle alone, and when the PING that asked had reached it. The
    answer is the first STATUS the particle began to send after the PING was in (a periodic one
    already on its way would report the counters of an earlier moment)."""
    swarm = base.swarm
    base.send(Ping(target=swarm.ids[index]))
    raw = base.sent[-1][1]
    found: list[tuple[Status, float]] = []

    def answered() -> bool:
        copy = next(
            (
                r
                for r in swarm.air.receptions
                if r.receiver == index and r.packet.source == BASE and r.packet.data == raw
            ),
            None,
        )
        if copy is None:
            return False
        assert copy.delivered
        sent = bytes(b.value for b in swarm.emulated.sims[index].uart if b.cycle >= copy.last)
        for frame in StreamDecoder().feed(sent):
            if isinstance(frame.message, Status):
                found.append((frame.message, copy.last / CPU_HZ))
                return True
        return False

    assert swarm.run_until_true(answered, 0.5)
    return found[0]


def test_sprayed_garbage_is_counted_and_leaves_every_particle_working(swarm: SimSwarm) -> None:
    base = BaseStation(swarm)
    swarm.run_for(0.3)
    before = base.ping_all()
    assert sorted(before) == swarm.ids

    rng = random.Random(2024)
    sprayed = spray(swarm, rng, SPRAY_S / 2)
    during = base.ping_all(timeout_s=1.5)
    assert sorted(during) == swarm.ids, "a particle stopped answering under noise"
    sprayed += spray(swarm, rng, SPRAY_S / 2)
    assert StreamDecoder().feed(sprayed) == []
    swarm.run_for(0.3)  # quiet: every parser has timed out on whatever it held

    for index, sim in enumerate(swarm.emulated.sims):
        particle_id = swarm.ids[index]
        assert sim.resets == [] and sim.crashed_cycle is None, f"particle {particle_id}"
        # The servo never missed a 50 Hz frame: the main loop and its timer kept running.
        assert missed_frames(sim.servo_pulses) == 0
        assert max(abs(e) for e in period_errors_us(sim.servo_pulses)) <= SERVO_JITTER_US

        status, pinged_s = status_after_quiet_ping(base, index)
        # What its parser dropped is what was damaged in the bytes that reached it (the host's
        # decoder, given the same bytes and the same 100 ms timeout, counts the same).
        _, expected = swarm.received(index, until_s=pinged_s)
        assert status.rx_frames == expected.frames
        assert status.rx_bad_crc == expected.bad_crc
        assert status.rx_bad_length == expected.bad_length + expected.truncated
        assert status.rx_skipped_bytes == expected.skipped_bytes
        assert status.rx_bad_crc + status.rx_bad_length > 20
        assert status.rx_skipped_bytes > 1000
        assert status.state == State.IDLE and status.run_id == before[particle_id].run_id
        assert status.resets == before[particle_id].resets

    # And each one still obeys START and STOP.
    started = base.send(
        Start(
            run_id=5,
            method=Method.COUNTING,
            cycle_steps=75,
            wave_size=0,
            update_interval_s=0,
            phototaxis=0,
        )
    )
    swarm.run_until(started + ROUND_MS / 1000 + 0.1)
    statuses = base.ping_all()
    assert [statuses[i].s_n for i in swarm.ids] == list(range(1, COUNT + 1))
    assert all(statuses[i].state in (State.WAITING, State.CYCLING) for i in swarm.ids)
    base.send(Stop())
    swarm.run_for(1.0)
    statuses = base.ping_all()
    assert all(statuses[i].state == State.IDLE for i in swarm.ids)
