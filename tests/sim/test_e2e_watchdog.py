"""An emulated particle whose watchdog fires rejoins the swarm with its id and its settings."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from particlebot.protocol import (
    GetParam,
    Method,
    Param,
    ParamResult,
    ParamValue,
    SetParam,
    Start,
    State,
)
from particlebot.sim.swarm import Level, SimSwarm, SwarmConfig
from particlebot.sim.swarm.base import BaseStation

pytestmark = [pytest.mark.usefixtures("built_images"), pytest.mark.e2e]

COUNT = 3
HUNG = 1  # index of the particle running the fault-injection build
MCUSR_WATCHDOG = 0x08


@pytest.fixture
def swarm() -> Iterator[SimSwarm]:
    config = SwarmConfig(
        level=Level.EMULATED, count=COUNT, fault_elf=(HUNG,), params={Param.ROUND_MS: 1000}
    )
    with SimSwarm(config) as emulated:
        yield emulated


def param_value(base: BaseStation, particle_id: int, param: Param, since_s: float) -> ParamValue:
    """The PARAM_VALUE particle_id sends about param after since_s (runs until it comes)."""

    def answers() -> list[ParamValue]:
        return [
            message
            for heard, message in base.frames(ParamValue, since_s)
            if isinstance(message, ParamValue)
            and heard.frame.sender == particle_id
            and message.param == param
        ]

    assert base.swarm.run_until_true(lambda: bool(answers()), 0.5), "no PARAM_VALUE"
    return answers()[0]


def test_watchdog_reset_keeps_the_particles_id_and_settings(swarm: SimSwarm) -> None:
    base = BaseStation(swarm)
    swarm.run_for(0.3)
    hung_id = swarm.ids[HUNG]
    asked = base.send(SetParam(target=hung_id, param=Param.COUNT_TOLERANCE, value=37))
    answer = param_value(base, hung_id, Param.COUNT_TOLERANCE, asked)
    assert (answer.result, answer.value) == (ParamResult.OK, 37)
    before = base.ping_all()[hung_id]

    sim = swarm.emulated.sims[HUNG]
    sim.set_fault_pin(True)
    hung_s = swarm.time_s
    assert swarm.run_until_true(lambda: bool(sim.resets), 1.0), "the watchdog did not fire"
    sim.set_fault_pin(False)
    assert sim.resets[0].by_watchdog
    assert 0.2 <= sim.resets[0].time_s - hung_s <= 0.3  # WDTO_250MS
    swarm.run_for(0.3)

    after = base.ping_all()
    assert sorted(after) == swarm.ids  # back under its own id
    status = after[hung_id]
    assert status.last_reset_cause & MCUSR_WATCHDOG
    assert status.resets == before.resets + 1
    assert status.uptime_ms < 1000
    asked = base.send(GetParam(target=hung_id, param=Param.COUNT_TOLERANCE))
    answer = param_value(base, hung_id, Param.COUNT_TOLERANCE, asked)
    assert (answer.result, answer.value) == (ParamResult.OK, 37)
    for index, other in enumerate(swarm.emulated.sims):
        if index != HUNG:
            assert other.resets == []

    # It takes part in the next run like the others.
    started = base.send(
        Start(
            run_id=2,
            method=Method.COUNTING,
            cycle_steps=75,
            wave_size=0,
            update_interval_s=0,
            phototaxis=0,
        )
    )
    swarm.run_until(started + 1.1)
    statuses = base.ping_all()
    assert [statuses[i].s_n for i in swarm.ids] == list(range(1, COUNT + 1))
    assert all(statuses[i].group_size == COUNT for i in swarm.ids)
    assert all(statuses[i].state in (State.WAITING, State.CYCLING) for i in swarm.ids)
