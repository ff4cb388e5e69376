"""The console's STOP contracts every emulated particle's servo within a second, lossy air too."""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import pytest

from particlebot.protocol import (
    BASE_STATION_ID,
    PARAM_SPECS,
    Message,
    Method,
    Param,
    State,
    Stop,
    StreamDecoder,
    decode_frame,
    encode_frame,
)
from particlebot.session import ReceivedFrame
from particlebot.sim.air.medium import BASE, AirPacket
from particlebot.sim.clock import CPU_HZ
from particlebot.sim.particles.emulated.harness import ServoPulse
from particlebot.sim.particles.emulated.particles import node_name
from particlebot.sim.particles.emulated.servo import contracted_width
from particlebot.sim.swarm import Level, SimSwarm, SwarmConfig
from particlebot.sim.swarm.base import packet_frames
from particlebot.swarm.tracker import SwarmTracker

pytestmark = [pytest.mark.usefixtures("built_images"), pytest.mark.e2e]

COUNT = 5
CYCLE_STEPS = 75
ROUND_MS = 1000
CONTRACTED_US = PARAM_SPECS[Param.SERVO_CAL_0].default
EXPANDED_US = CONTRACTED_US + 100
# An edge of the pulse waits while another interrupt (millis, Serial1) finishes; the longest,
# Serial1's transmit interrupt, takes ~120 cycles (15 us). benchmarks/bench_sim.py saw 14.25 us.
SERVO_JITTER_US = 20
STOP_WITHIN_S = 1.0
"""From the console's STOP command to the last servo at the contracted pulse (the issue's
requirement)."""
WATCH_AFTER_STOP_S = 3.5


class Console:
    """The console's model (which repeats START and STOP until particles confirm them) driving an
    emulated swarm from this thread, polled as often as the live console polls it: what the
    session thread and the UI's timer do for a real radio."""

    def __init__(self, swarm: SimSwarm) -> None:
        self.swarm = swarm
        self.seq = itertools.count()
        self.model = SwarmTracker(self, lambda: swarm.time_s)
        self.sent: list[tuple[float, bytes]] = []
        self.decoder = StreamDecoder()
        swarm.add_base_listener(self._on_packet)

    def send(self, message: Message) -> None:
        raw = encode_frame(message, BASE_STATION_ID, next(self.seq) % 256)
        self.sent.append((self.swarm.time_s, raw))
        self.swarm.send_from_base(raw)

    def note(self, text: str) -> None:
        pass

    def _on_packet(self, source: int, data: bytes, time_s: float) -> None:
        for frame in self.decoder.feed(data, source):
            self.model.on_frame(ReceivedFrame(time_s, node_name(source), frame))

    def run_for(self, seconds: float) -> None:
        end = self.swarm.time_s + seconds
        while self.swarm.time_s < end:
            self.swarm.run_for(0.05)  # particlebot.console.app.POLL_S
            self.model.poll()


def is_stop(packet: AirPacket) -> bool:
    return packet.source == BASE and any(
        frame.type == Stop.MESSAGE_TYPE for frame in packet_frames(packet)
    )


def stops_received_s(swarm: SimSwarm, index: int) -> list[float]:
    """When each STOP that reached particle index had fully arrived."""
    return [
        copy.last / CPU_HZ
        for copy in swarm.air.receptions
        if copy.receiver == index and copy.delivered and is_stop(copy.packet)
    ]


def is_contracted(pulse: ServoPulse) -> bool:
    return abs(pulse.width_us - CONTRACTED_US) <= SERVO_JITTER_US


def contracted_since_s(pulses: Sequence[ServoPulse]) -> float:
    """Start of the first pulse of the contracted stretch that lasts to the end (inf if the last
    pulse is not contracted)."""
    since = math.inf
    for pulse in reversed(pulses):
        if not is_contracted(pulse):
            break
        since = pulse.start_s
    return since


@dataclass(frozen=True)
class Air:
    loss: float
    """Random loss of every copy of every packet at every receiver."""
    first_stop_lost: bool
    """The first STOP misses the particle that is expanded furthest when it goes out."""


AIRS = {
    "no loss": Air(0.0, first_stop_lost=False),
    "first STOP lost": Air(0.0, first_stop_lost=True),
    "20% loss": Air(0.2, first_stop_lost=False),
}


@dataclass
class Outcome:
    swarm: SimSwarm
    console: Console
    commanded_s: float
    """When the console's STOP command sent its first copy."""
    unlucky: int | None
    """The index of the particle that missed the first STOP for sure, if one did."""
    widths_at_stop: list[float]


def stop_a_running_swarm(swarm: SimSwarm, air: Air) -> Outcome:
    """Lists the particles, STARTs them, and STOPs them while two or more are expanded."""
    unlucky: list[int] = []
    taken: list[AirPacket] = []

    def drop(packet: AirPacket, receiver: int) -> bool:
        if unlucky and receiver == unlucky[0] and not taken and is_stop(packet):
            taken.append(packet)
            return True
        return False

    swarm.air.drop = drop
    console = Console(swarm)
    for _ in range(10):  # as a person would: PING until every particle is listed
        console.model.ping()
        console.run_for(0.5)
        if len(console.model.rows()) == COUNT:
            break
    assert sorted(row.id for row in console.model.rows()) == swarm.ids

    start = console.model.start(Method.COUNTING, cycle_steps=CYCLE_STEPS)

    def widths() -> list[float]:
        return [sim.servo_pulses[-1].width_us for sim in swarm.emulated.sims]

    for _ in range(200):
        console.run_for(0.05)
        if start.done and sum(w > EXPANDED_US for w in widths()) >= 2:
            break
    assert start.success, start.outcome
    at_stop = widths()
    assert sum(w > EXPANDED_US for w in at_stop) >= 2
    if air.first_stop_lost:
        unlucky.append(max(range(COUNT), key=lambda i: at_stop[i]))
    stop = console.model.stop()
    commanded_s = console.sent[-1][0]
    console.run_for(WATCH_AFTER_STOP_S)
    assert stop.done and stop.success, stop.outcome
    assert all(row.state == State.IDLE for row in console.model.rows())
    return Outcome(swarm, console, commanded_s, unlucky[0] if unlucky else None, at_stop)


@pytest.fixture(params=list(AIRS), scope="module")
def outcome(request: pytest.FixtureRequest) -> Iterator[Outcome]:
    """One swarm per kind of air, stopped once; the tests read what happened."""
    air = AIRS[request.param]
    config = SwarmConfig(
        level=Level.EMULATED, count=COUNT, loss=air.loss, params={Param.ROUND_MS: ROUND_MS}, seed=7
    )
    with SimSwarm(config) as swarm:
        yield stop_a_running_swarm(swarm, air)


def test_every_servo_is_contracted_within_a_second_of_the_consoles_stop(outcome: Outcome) -> None:
    for index, sim in enumerate(outcome.swarm.emulated.sims):
        since = contracted_since_s(sim.servo_pulses)
        assert since - outcome.commanded_s < STOP_WITHIN_S, (
            f"particle {outcome.swarm.ids[index]} contracted {since - outcome.commanded_s:.3f} s "
            "after the STOP command"
        )
        # ... and it stays there: two seconds and more of contracted frames, the last included.
        resting = [p for p in sim.servo_pulses if p.start_s >= since]
        assert resting[-1].start_s - since >= WATCH_AFTER_STOP_S - STOP_WITHIN_S - 0.1
        assert abs(contracted_width(resting) - CONTRACTED_US) <= 1


def test_stop_went_out_as_a_burst_of_four_copies_in_three_tenths_of_a_second(
    outcome: Outcome,
) -> None:
    stops = [at for at, raw in outcome.console.sent if decode_frame(raw).type == Stop.MESSAGE_TYPE]
    offsets = [round(at - outcome.commanded_s, 3) for at in stops[:4]]
    assert offsets == [0.0, 0.1, 0.2, 0.3]


@pytest.mark.parametrize("outcome", ["first STOP lost"], indirect=True)
def test_the_particle_that_missed_the_first_stop_obeyed_a_later_copy_in_time(
    outcome: Outcome,
) -> None:
    index = outcome.unlucky
    assert index is not None
    # The widest body of the swarm: the longest stop ramp of all, and it starts 0.1 s late.
    assert outcome.widths_at_stop[index] == max(outcome.widths_at_stop) > EXPANDED_US
    first_s = stops_received_s(outcome.swarm, index)[0]
    assert first_s - outcome.commanded_s >= 0.1
    since = contracted_since_s(outcome.swarm.emulated.sims[index].servo_pulses)
    assert since - outcome.commanded_s < STOP_WITHIN_S


@pytest.mark.parametrize("outcome", ["20% loss"], indirect=True)
def test_random_loss_took_copies_of_stop_away_and_every_particle_still_got_one(
    outcome: Outcome,
) -> None:
    medium = outcome.swarm.air
    copies = [r for r in medium.receptions if r.receiver != BASE and is_stop(r.packet)]
    lost = [r for r in copies if r.lost]
    assert lost, "the seeded losses spared every STOP: this air tests nothing; change the seed"
    for index in range(COUNT):
        assert stops_received_s(outcome.swarm, index)
