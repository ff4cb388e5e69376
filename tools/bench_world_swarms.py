"""Speed of simulated swarms in the world: simulated seconds per wall second for virtual particles
(the firmware logic) and emulated ones (the image in simavr), STARTed and cycling.

    python tools/bench_world_swarms.py [--virtual 10 100 1000] [--emulated 1 5 10]

Each swarm is a blob (SI Algorithm 5) 1.5 m from the lamp, STARTed with method A at T = 3 s; the
clock runs from the end of the estimation round, so every particle cycles or pauses on its wave.
Goals (issue 8): 10 virtual particles at least 50x real time, 5 emulated at least 2x.
"""

from __future__ import annotations

import argparse
import os
import time

from particlebot.protocol import Method, Start
from particlebot.sim.scenarios import presets
from particlebot.sim.swarm import Level, SimSwarm, SwarmConfig
from particlebot.sim.swarm.base import BaseStation

SETTLE_S = 4.0
"""START, then the 3 s round: the waves have begun."""


def speed(level: Level, count: int, simulated_s: float) -> float:
    config = SwarmConfig(
        scenario=presets.blob(count, start=1.5, seed=1), level=level, keep_history=False
    )
    with SimSwarm(config) as swarm:
        base = BaseStation(swarm)
        swarm.run_for(0.5)
        base.send(
            Start(
                run_id=1,
                method=Method.DIRECT,
                cycle_steps=150,
                wave_size=0,
                update_interval_s=0,
                phototaxis=0,
            )
        )
        swarm.run_for(SETTLE_S)
        began = time.perf_counter()
        swarm.run_for(simulated_s)
        return simulated_s / (time.perf_counter() - began)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--virtual", type=int, nargs="*", default=[10, 100, 1000])
    parser.add_argument("--emulated", type=int, nargs="*", default=[1, 5, 10])
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    for count in args.virtual:
        seconds = 120.0 if count <= 10 else 30.0 if count <= 100 else 6.0
        achieved = speed(Level.NATIVE, count, seconds)
        print(f"virtual  {count:5d} particles: {achieved:8.1f} x real time")
    for count in args.emulated:
        seconds = 20.0 if count <= 5 else 10.0
        achieved = speed(Level.EMULATED, count, seconds)
        print(f"emulated {count:5d} particles: {achieved:8.1f} x real time")


if __name__ == "__main__":
    main()
