"""The flashed image finds the lamp: five emulated particles (particle.elf in simavr) in a line
1.5 m from a lamp, STARTed with phototaxis on through emulated://, crawl toward it in the world.
(research/closed_loop.py --level emulated runs the same for ten minutes; README has the figures.)"""

from __future__ import annotations

from pathlib import Path

import pytest

from particlebot.analysis.sources import load_source
from particlebot.plots import read_records
from particlebot.sim.swarm.records import read_world
from particlebot.swarm.api import Swarm

pytestmark = [pytest.mark.usefixtures("built_images"), pytest.mark.e2e]

URL = "emulated://5?speed=max&scenario=line&start=1.5&seed=3"


def test_a_line_of_emulated_particles_crawls_toward_the_lamp(tmp_path: Path) -> None:
    with Swarm.open(URL, log_dir=tmp_path) as swarm:
        swarm.wait_for(count=5, timeout=15)
        # T = 1.5 s: the 3 s round, then a wave of five every T + t_p = 4.5 s.
        run = swarm.start("D", cycle_steps=75, phototaxis=True)
        swarm.sleep(12.5)
        ranks = {p.id: p.s_n for p in swarm.particles()}
        swarm.stop()
        log = swarm.log_path
    assert run.particles == (1, 2, 3, 4, 5)
    assert ranks == {1: 1, 2: 2, 3: 3, 4: 4, 5: 5}  # the line's order from the lamp
    assert log is not None
    world = read_world(read_records(log).records)
    assert world is not None and world.level == "emulated"
    moved = world.x[0] - world.x[-1]  # the lamp is at x = 0, the line along +x
    # Two waves: every particle 3-9 cm nearer the lamp (measured: 5.0-7.2 cm).
    assert all(0.03 < m < 0.09 for m in moved), moved
    (series,) = load_source(log)
    assert series.kind == "log" and series.cycle_s == pytest.approx(4.5, abs=0.05)
