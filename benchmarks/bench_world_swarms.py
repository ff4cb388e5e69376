"""Speed of simulated swarms in the world: simulated seconds per wall second for virtual particles
(the firmware logic) and emulated ones (the image in simavr), STARTed and cycling.

    python benchmarks/bench_world_swarms.py [--virtual 10 100 1000] [--emulated 1 5 10]

Each swarm is a blob (SI Algorithm 5) 1.5 m from the lamp, STARTed with method A at T = 3 s; the
clock runs from the end of the estimation round, so every particle cycles or pauses on its wave.
Goals: 10 virtual particles at least 50x real time, 5 emulated at least 2x.

On a shared machine the wall-clock figure depends on who else runs, so each line also gives the
CPU time the swarm used (this process and its simavr children) per simulated second, and the
speed that CPU time allows on this machine's cores when nothing else runs: simavr's processes run
in parallel, so K emulated particles can use every core.
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


def cpu_seconds() -> float:
    """CPU time of this process and its live children (the simavr processes) so far."""
    tick = os.sysconf("SC_CLK_TCK")
    total = time.process_time()
    pid = os.getpid()
    with open(f"/proc/{pid}/task/{pid}/children", encoding="ascii") as listing:
        children = listing.read().split()
    for child in children:
        try:
            with open(f"/proc/{child}/stat", encoding="ascii") as stat:
                fields = stat.read().rsplit(")", 1)[1].split()
        except OSError:
            continue  # ended meanwhile
        total += (int(fields[11]) + int(fields[12])) / tick  # utime, stime
    return total


def speed(level: Level, count: int, simulated_s: float) -> tuple[float, float]:
    """(simulated seconds per wall second, CPU seconds per simulated second)."""
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
        cpu_began = cpu_seconds()
        swarm.run_for(simulated_s)
        cpu = cpu_seconds() - cpu_began
        return simulated_s / (time.perf_counter() - began), cpu / simulated_s


def report(kind: str, count: int, achieved: float, cpu_per_s: float) -> None:
    cores = os.cpu_count() or 1
    # One Python process steps the world and the native particles: it cannot use a second core.
    # K simavr processes run a quantum each in parallel, then wait for this one: K cores at most.
    usable = min(cores, count) if kind.strip() == "emulated" else 1
    bound = usable / cpu_per_s
    print(
        f"{kind} {count:5d} particles: {achieved:8.1f} x real time; "
        f"{cpu_per_s:.3f} CPU s per simulated s, so {bound:.1f} x on {usable} free core(s)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--virtual", type=int, nargs="*", default=[10, 100, 1000])
    parser.add_argument("--emulated", type=int, nargs="*", default=[1, 5, 10])
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    for count in args.virtual:
        seconds = 120.0 if count <= 10 else 30.0 if count <= 100 else 6.0
        report("virtual ", count, *speed(Level.NATIVE, count, seconds))
    for count in args.emulated:
        seconds = 20.0 if count <= 5 else 10.0
        report("emulated", count, *speed(Level.EMULATED, count, seconds))


if __name__ == "__main__":
    main()
