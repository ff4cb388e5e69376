#!/usr/bin/env python3
"""Measures simulate-like stepping of a large swarm on one thread, on all of numba's, and with the
world's own choice (the default), on an idle machine and beside busy loops it starts itself;
prints a table of real-time factors and checks that every choice gives the same bits.

Run it on an otherwise idle machine (it makes its own load):
    PYTHONPATH=host python benchmarks/bench_threads.py            # about 3 minutes
    PYTHONPATH=host python benchmarks/bench_threads.py --layers workqueue,omp
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass, replace

import numba
import numpy as np

from particlebot.sim.runs.run import CHUNK_WALL_S
from particlebot.sim.scenarios.build import build_world
from particlebot.sim.warmup import warm_up
from particlebot.sim.world.world import World

BUSY_LOOP = "while True: pass"


def quick_world(particles: int, seed: int) -> World:
    """`simulate --particles N` without a file: a blob walking toward a lamp on its -x side."""
    from particlebot.commands.simulate import quick_scenario

    return build_world(replace(quick_scenario(particles), seed=seed)).world


def step_for(world: World, wall_s: float) -> tuple[float, dict[int, int]]:
    """Steps in chunks of about CHUNK_WALL_S, as `simulate` does, for `wall_s`; (simulated
    seconds per wall second, compiled calls per thread count)."""
    began = time.monotonic()
    start_t = world.t
    chunk = 1
    calls: dict[int, int] = {}
    while time.monotonic() - began < wall_s:
        tick = time.monotonic()
        world.step(chunk)
        calls[world.threads] = calls.get(world.threads, 0) + 1
        took = time.monotonic() - tick
        chunk = max(1, min(int(chunk / max(took, 1e-6) * CHUNK_WALL_S), 4 * chunk))
    return (world.t - start_t) / (time.monotonic() - began), calls


def digest(world: World) -> str:
    state = world.state()
    hasher = hashlib.sha256()
    for row in (state.x, state.y, state.vx, state.vy, world.radii()):
        hasher.update(np.ascontiguousarray(row).tobytes())
    return hasher.hexdigest()[:16]


@contextmanager
def busy_loops(count: int) -> Iterator[None]:
    """`count` processes that each hold a core (as other users' jobs do)."""
    loops = [subprocess.Popen([sys.executable, "-c", BUSY_LOOP]) for _ in range(count)]
    try:
        time.sleep(1.0)  # let them get going
        yield
    finally:
        for loop in loops:
            loop.kill()
        for loop in loops:
            loop.wait()


@dataclass(frozen=True)
class Row:
    load: str
    threads: str
    factor: float
    """Simulated seconds per wall second."""
    calls: dict[int, int]


def measure(particles: int, wall_s: float, busy: int) -> list[Row]:
    most: int = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
    choices: list[tuple[str, int | None]] = [("1 thread", 1), (f"{most} threads", most)]
    choices.append(("chosen (default)", None))
    rows: list[Row] = []
    for load, loops in (("idle", 0), (f"{busy} busy loops", busy)):
        with busy_loops(loops):
            for name, threads in choices:
                world = quick_world(particles, seed=1)
                world.thread_count = threads
                factor, calls = step_for(world, wall_s)
                rows.append(Row(load, name, factor, calls))
                print(f"  {load:14} {name:18} {factor:7.2f}x real time  calls {calls}", flush=True)
    return rows


def same_bits(particles: int, steps: int) -> dict[str, str]:
    """The swarm after `steps` steps (in calls of 10) on each choice: equal digests."""
    most: int = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
    digests = {}
    for name, threads in (("1", 1), (str(most), most), ("chosen", None)):
        world = quick_world(particles, seed=2)
        world.thread_count = threads
        for _ in range(steps // 10):
            world.step(10)
        digests[name] = digest(world)
    return digests


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--particles", type=int, default=10_000)
    parser.add_argument("--seconds", type=float, default=20.0, help="wall time per measurement")
    parser.add_argument("--busy", type=int, default=2, help="busy loops beside the loaded runs")
    parser.add_argument("--bits-steps", type=int, default=300)
    parser.add_argument(
        "--layers", help="numba threading layers to compare, e.g. workqueue,omp (each in a child)"
    )
    parser.add_argument("--json", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.layers:
        for layer in args.layers.split(","):
            print(f"== NUMBA_THREADING_LAYER={layer}", flush=True)
            argv = [sys.executable, __file__, "--particles", str(args.particles), "--seconds",
                    str(args.seconds), "--busy", str(args.busy), "--bits-steps",
                    str(args.bits_steps)]  # fmt: skip
            env = {**os.environ, "NUMBA_THREADING_LAYER": layer}
            subprocess.run(argv, env=env, check=False)
        return 0

    most: int = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
    print(f"cores {os.cpu_count()}, numba threads {most}", flush=True)
    began = time.monotonic()
    warm_up()  # compiling is not stepping
    spin = os.environ.get("GOMP_SPINCOUNT", "libgomp's default")
    wait = os.environ.get("OMP_WAIT_POLICY", "unset")
    print(f"kernels ready in {time.monotonic() - began:.0f} s; threading layer "
          f"{numba.threading_layer()}, GOMP_SPINCOUNT {spin}, OMP_WAIT_POLICY {wait}",
          flush=True)  # fmt: skip
    rows = measure(args.particles, args.seconds, args.busy)
    digests = same_bits(args.particles, args.bits_steps)

    print()
    print(f"{args.particles:,} particles, {args.seconds:g} s of simulate-like stepping each")
    print("| load | threads | x real time | best / this |")
    print("| --- | --- | ---: | ---: |")
    for load in dict.fromkeys(r.load for r in rows):
        mine = [r for r in rows if r.load == load]
        best = max(r.factor for r in mine)
        for r in mine:
            print(f"| {load} | {r.threads} | {r.factor:.2f} | {best / r.factor:.2f} |")
    equal = len(set(digests.values())) == 1
    print(f"same bits after {args.bits_steps} steps on each choice: {'yes' if equal else 'NO'} "
          f"{digests}")  # fmt: skip
    if args.json:
        print(json.dumps({"rows": [asdict(r) for r in rows], "digests": digests}))
    return 0 if equal else 1


if __name__ == "__main__":
    sys.exit(main())
