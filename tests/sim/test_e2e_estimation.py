"""Five emulated particles in a line from a lamp estimate S_n and start the wave on time."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from particlebot.firmware.native import estimate
from particlebot.protocol import (
    BROADCAST_ID,
    PARAM_SPECS,
    Intensity,
    Method,
    Param,
    ParamResult,
    ParamValue,
    SetParam,
    Start,
    State,
)
from particlebot.sim.air.medium import BASE
from particlebot.sim.clock import CPU_HZ
from particlebot.sim.particles.emulated.servo import (
    bursts,
    contracted_width,
    cycle_starts,
    servo_step_s,
)
from particlebot.sim.swarm import Level, SimSwarm, SwarmConfig
from particlebot.sim.swarm.base import BaseStation

pytestmark = [pytest.mark.usefixtures("built_images"), pytest.mark.e2e]

STEP_S = servo_step_s()  # one servo step, as the firmware defines it
COUNT = 5
CYCLE_STEPS = 75
T_S = CYCLE_STEPS * STEP_S
ROUND_MS = 1000
ROUND_S = ROUND_MS / 1000
# The particle stamps START with its millisecond clock (servo frames counted on Timer1), read once
# per pass of its main loop and truncated: within a millisecond or so of the last byte's arrival.
CLOCK_TICK_S = 0.003


@pytest.fixture
def swarm() -> Iterator[SimSwarm]:
    with SimSwarm(SwarmConfig(level=Level.EMULATED, count=COUNT)) as emulated:
        yield emulated


def set_round_length(base: BaseStation) -> None:
    """ROUND_MS for every particle over the air, confirmed by each."""
    asked = base.send(SetParam(target=BROADCAST_ID, param=Param.ROUND_MS, value=ROUND_MS))

    def confirmed() -> set[int]:
        return {
            heard.frame.sender
            for heard, message in base.frames(ParamValue, asked)
            if isinstance(message, ParamValue)
            and message.param == Param.ROUND_MS
            and message.result == ParamResult.OK
            and message.value == ROUND_MS
        }

    assert base.swarm.run_until_true(lambda: confirmed() == set(base.swarm.ids), 1.0)


def start_received_s(swarm: SimSwarm, index: int, start_frame: bytes) -> float:
    """When the START frame's last byte reached particle index's serial port."""
    copies = [
        r
        for r in swarm.air.receptions
        if r.receiver == index and r.packet.source == BASE and r.packet.data == start_frame
    ]
    assert copies and copies[0].delivered
    return copies[0].last / CPU_HZ


def heard_in_round(swarm: SimSwarm, index: int, run_id: int, until_s: float) -> dict[int, int]:
    """The other particles' INTENSITY readings of round 0 that reached particle index's firmware
    before its round ended, by sender (a later copy replaces an earlier one, as in the firmware)."""
    frames, _ = swarm.received(index, until_s=until_s)
    readings: dict[int, int] = {}
    for _, frame in frames:
        message = frame.message
        if isinstance(message, Intensity) and message.run_id == run_id and message.round == 0:
            readings[frame.sender] = message.intensity
    readings.pop(swarm.ids[index], None)
    return readings


def expansions_s(swarm: SimSwarm, index: int, after_s: float) -> list[float]:
    """Start of each whole expansion cycle of particle index after after_s, read from its servo
    pulses: the frame that carried the cycle's step 0, right before the first wider pulse."""
    pulses = swarm.emulated.sims[index].servo_pulses
    resting = [p for p in pulses if p.start_s < after_s][-50:]
    later = [p for p in pulses if p.start_s >= after_s]
    contracted = contracted_width(resting)
    for burst in bursts(later, contracted, 30.0):
        if burst.last + 1 < len(later):
            # One cycle (steps ~4 .. n-4 are this far out), reaching R_max.
            assert CYCLE_STEPS - 12 <= burst.frames <= CYCLE_STEPS, burst
            assert burst.peak_us >= PARAM_SPECS[Param.SERVO_CAL_8].default - 5, burst
    return cycle_starts(later, CYCLE_STEPS, contracted)


@pytest.mark.parametrize(
    "method",
    [Method.COUNTING, Method.DIRECT, Method.LINEAR, Method.NONLINEAR],
    ids=lambda method: method.name,
)
def test_each_particle_estimates_as_the_firmware_library_does_and_moves_at_its_turn(
    swarm: SimSwarm, method: Method
) -> None:
    base = BaseStation(swarm)
    swarm.run_for(0.3)
    set_round_length(base)
    before = base.ping_all()
    assert sorted(before) == swarm.ids
    assert all(status.state == State.IDLE for status in before.values())

    run_id = 3
    base.send(
        Start(
            run_id=run_id,
            method=int(method),
            cycle_steps=CYCLE_STEPS,
            wave_size=0,
            update_interval_s=0,
            phototaxis=0,
        )
    )
    start_frame = base.sent[-1][1]
    swarm.run_for(0.1)
    received = [start_received_s(swarm, i, start_frame) for i in range(COUNT)]
    common_start = [t + ROUND_S for t in received]
    swarm.run_until(max(common_start) + 0.05)
    statuses = base.ping_all()
    assert sorted(statuses) == swarm.ids

    own_broadcast = {
        heard.frame.sender: message.intensity
        for heard, message in base.frames(Intensity)
        if isinstance(message, Intensity) and message.run_id == run_id
    }
    s_n: list[int] = []
    for index, particle_id in enumerate(swarm.ids):
        status = statuses[particle_id]
        assert status.run_id == run_id and status.method == method
        assert status.state in (State.WAITING, State.CYCLING), status
        heard = heard_in_round(swarm, index, run_id, common_start[index])
        if method == Method.DIRECT:
            assert not own_broadcast  # method A needs no radio
            own = status.intensity
        else:
            assert sorted(heard) == sorted(set(swarm.ids) - {particle_id})
            assert status.group_size == COUNT
            own = own_broadcast[particle_id]
        expected = estimate(method, own, list(heard.values()))
        assert status.s_n == expected, f"particle {particle_id}"
        s_n.append(status.s_n)
    if method == Method.COUNTING:
        # The line runs away from the lamp: rank by distance, 1 nearest.
        assert s_n == list(range(1, COUNT + 1))
    if method == Method.DIRECT:
        assert s_n == sorted(s_n) and s_n[-1] > s_n[0]

    # N of eq. 3: the group heard (B-D), else the WAVE_SIZE parameter (A).
    wave = PARAM_SPECS[Param.WAVE_SIZE].default if method == Method.DIRECT else COUNT
    pause_s = (wave - 1) * T_S / 2
    delays_s = [(s - 1) * T_S / 2 for s in s_n]
    # The second cycles' rising flanks must be in: 0.5 s.
    swarm.run_until(max(common_start) + max(delays_s) + T_S + pause_s + 0.5)
    for index in range(COUNT):
        starts = expansions_s(swarm, index, received[index])
        assert len(starts) >= 2, f"particle {swarm.ids[index]}: {starts}"
        late_s = starts[0] - (common_start[index] + delays_s[index])
        # Step 0 goes out in the first 50 Hz frame that begins at or after its instant.
        assert -CLOCK_TICK_S <= late_s <= STEP_S + CLOCK_TICK_S, f"particle {swarm.ids[index]}"
        pause_measured = starts[1] - starts[0] - T_S
        assert abs(pause_measured - pause_s) <= STEP_S, f"particle {swarm.ids[index]}"
