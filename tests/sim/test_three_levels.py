"""One scenario at all three levels of fidelity: the vectorised model of the firmware, the firmware
logic (native) and the flashed image (emulated), each driving the same bodies in the same world.

They agree where they should: every particle gets the same S_n, and the blob crawls toward the
lamp by about the same distance. (Not by exactly the same: the model idealises the radio, and
bodies in contact amplify any difference of a few milliseconds into millimetres.)"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from particlebot.protocol import Method, Start
from particlebot.sim.particles.model.firmware import FirmwareController, FirmwareSettings
from particlebot.sim.scenarios import presets
from particlebot.sim.scenarios.build import build_world
from particlebot.sim.scenarios.scenario import ControllerKind, ControllerSpec
from particlebot.sim.swarm import Level, SimSwarm, SwarmConfig
from particlebot.sim.swarm.base import BaseStation

pytestmark = [pytest.mark.usefixtures("built_images"), pytest.mark.e2e]

# A blob of four touching particles (SI Algorithm 5, seeded), half a metre from the lamp; method
# D at T = 1.5 s: the round (3 s), then waves of T + t_p = 1.5 s + 3 x 0.75 s, six in all.
SCENARIO = presets.blob(4, start=0.5, seed=2)
CYCLE_STEPS = 75
START_S = 0.5
RUN_S = 24.0


def centroid_distance(x: list[float], y: list[float]) -> float:
    lamp = SCENARIO.lamp
    return math.hypot(float(np.mean(x)) - lamp.x, float(np.mean(y)) - lamp.y)


def model() -> tuple[list[int], float]:
    """The vectorised firmware controller: every particle hears START at START_S."""
    settings = FirmwareSettings(method=Method.COUNTING, cycle_steps=CYCLE_STEPS, start_s=START_S)
    scenario = replace(
        SCENARIO, controller=ControllerSpec(kind=ControllerKind.FIRMWARE, firmware=settings)
    )
    world = build_world(scenario).world
    before = centroid_distance(*(list(a) for a in world.positions()))
    world.run(START_S + RUN_S)
    assert isinstance(world.controller, FirmwareController)
    after = centroid_distance(*(list(a) for a in world.positions()))
    return [int(s) for s in world.controller.s_n], before - after


def firmware(level: Level) -> tuple[list[int], float]:
    """The swarm of firmware particles, STARTed by the base station at START_S."""
    with SimSwarm(SwarmConfig(scenario=SCENARIO, level=level, keep_history=False)) as swarm:
        base = BaseStation(swarm)
        swarm.run_until(START_S)
        before = swarm.snapshot()
        base.send(
            Start(
                run_id=1,
                method=Method.COUNTING,
                cycle_steps=CYCLE_STEPS,
                wave_size=0,
                update_interval_s=0,
                phototaxis=0,
            )
        )
        swarm.run_until(START_S + RUN_S)
        after = swarm.snapshot()
        statuses = base.ping_all()
        s_n = [statuses[particle_id].s_n for particle_id in swarm.ids]
    moved = centroid_distance([p.x for p in before], [p.y for p in before]) - centroid_distance(
        [p.x for p in after], [p.y for p in after]
    )
    return s_n, moved


def test_model_native_and_emulated_particles_rank_alike_and_crawl_to_the_lamp_alike() -> None:
    levels = {"model": model(), "native": firmware(Level.NATIVE)}
    levels["emulated"] = firmware(Level.EMULATED)
    ranks = {name: s_n for name, (s_n, _) in levels.items()}
    # Method D: each particle's S_n is its rank by distance to the lamp, at every level.
    assert ranks["model"] == ranks["native"] == ranks["emulated"]
    assert sorted(ranks["model"]) == [1, 2, 3, 4]
    moved = {name: distance for name, (_, distance) in levels.items()}
    # Six waves of a four-particle blob: 6.4, 6.6 and 7.2 cm toward the lamp (model, native,
    # emulated, as measured).
    assert all(distance > 0.04 for distance in moved.values()), moved
    assert max(moved.values()) < 1.5 * min(moved.values()), moved
