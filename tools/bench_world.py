#!/usr/bin/env python3
"""Measures the world's speed (particle-steps/s) and peak memory in a packed, actuating blob."""

from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import time

import numpy as np

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.world import Lamp, PhysicsParams, World
from particlebot.sim.world.world import Precision

DT_S = 0.01


def hex_blob(count: int, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """The `count` points of a hexagonal lattice (`spacing` apart) nearest the origin: a packed
    disc of contracted particles."""
    m = int(math.sqrt(count / 0.9) * 0.6) + 3
    i, j = np.meshgrid(np.arange(-m, m + 1), np.arange(-m, m + 1))
    x = (i + 0.5 * j).ravel() * spacing
    y = (j * math.sqrt(3) / 2).ravel() * spacing
    nearest = np.argsort(x * x + y * y, kind="stable")[:count]
    return x[nearest], y[nearest]


def measure(
    count: int, steps: int, warm: int, precision: Precision, shear: float
) -> dict[str, float]:
    """One size in this process: build, warm up (the blob starts cycling), time `steps`."""
    params = PhysicsParams(shear=shear)
    x, y = hex_blob(count, 2 * params.r_min)
    # A blob of 10^6 contracted particles is ~160 m across: widen the world's walls for it.
    half_width = max(params.half_width, float(np.abs(np.concatenate([x, y])).max()) * 1.5 + 5)
    params = PhysicsParams(half_width=half_width, shear=shear)
    lamp = Lamp(-float(np.abs(x).max()) - 20.0, 0.0)
    built = time.perf_counter()
    world = World(x, y, controller=PublishedController(), params=params, lamp=lamp, seed=1,
                  precision=precision)  # fmt: skip
    build_s = time.perf_counter() - built
    world.step(warm)
    rebuilds = world.rebuilds
    began = time.perf_counter()
    world.step(steps)
    wall = time.perf_counter() - began
    peak_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {
        "particles": count,
        "steps": steps,
        "wall_s": wall,
        "build_s": build_s,
        "particle_steps_per_s": count * steps / wall,
        "realtime_factor": steps * DT_S / wall,
        "peak_rss_mb": peak_kib / 1024,
        "rebuilds": world.rebuilds - rebuilds,
        "neighbour_width": int(world._nbr.shape[1]),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument(
        "--sizes", type=int, nargs="+", default=[1_000, 10_000, 100_000, 200_000, 1_000_000]
    )
    parser.add_argument("--steps", type=int, default=0, help="timed steps (default: ~1e8/N)")
    parser.add_argument("--warm", type=int, default=300, help="steps before timing")
    parser.add_argument("--precision", choices=["float64", "float32"], default="float64")
    parser.add_argument(
        "--shear",
        type=float,
        default=PhysicsParams().shear,
        help="contact shear (the published 40 makes packed blobs boil at dt = 0.01 s; 20 does not)",
    )
    parser.add_argument("--one", type=int, help=argparse.SUPPRESS)  # a child measuring one size
    args = parser.parse_args()
    if args.one is not None:
        steps = args.steps or max(100, min(20_000, int(2e8 / args.one)))
        print(json.dumps(measure(args.one, steps, args.warm, args.precision, args.shear)))
        return 0
    load = os.getloadavg()
    threads = os.environ.get("NUMBA_NUM_THREADS", os.cpu_count())
    print(f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; threads {threads};"
          f" {args.precision}; shear {args.shear:g}")  # fmt: skip
    print(f"{'particles':>10} {'steps':>6} {'particle-steps/s':>17} {'x real time':>11}"
          f" {'peak RSS MB':>11} {'rebuilds':>8}")  # fmt: skip
    for count in args.sizes:
        # Each size in its own process, so that its peak memory is its own.
        command = [sys.executable, __file__, "--one", str(count), "--warm", str(args.warm),
                   "--steps", str(args.steps), "--precision", args.precision,
                   "--shear", str(args.shear)]  # fmt: skip
        done = subprocess.run(command, capture_output=True, text=True, check=False)
        if done.returncode != 0:
            print(f"{count:>10} failed: {done.stderr.strip().splitlines()[-1:]}")
            continue
        r = json.loads(done.stdout.strip().splitlines()[-1])
        print(f"{count:>10} {r['steps']:>6} {r['particle_steps_per_s']:>17.3g}"
              f" {r['realtime_factor']:>11.2f} {r['peak_rss_mb']:>11.0f} {r['rebuilds']:>8}",
              flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
