#!/usr/bin/env python3
"""Measures the world's speed (particle-steps/s) and peak memory in a packed, actuating blob."""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

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
    cpu_began = time.process_time()
    world.step(steps)
    wall = time.perf_counter() - began
    cpu = time.process_time() - cpu_began
    peak_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return {
        "particles": count,
        "steps": steps,
        "wall_s": wall,
        "build_s": build_s,
        "particle_steps_per_s": count * steps / wall,
        "realtime_factor": steps * DT_S / wall,
        # CPU time of all threads: unlike wall time, hardly touched by others sharing the machine.
        "cpu_ns_per_particle_step": cpu / (count * steps) * 1e9,
        "peak_rss_mb": peak_kib / 1024,
        "rebuilds": world.rebuilds - rebuilds,
        "neighbour_width": int(world._nbr.shape[1]),
    }


LAMMPS_INPUT = """# 2-D granular discs of unit mass, Hooke contacts (k 1000, damping 10), packed
units si
dimension 2
boundary f f p
atom_style sphere
comm_modify vel yes
read_data blob.data
set group all mass 1.0
neighbor 0.02 bin
neigh_modify delay 0 every 1 check yes
pair_style gran/hooke 1000.0 NULL 10.0 NULL 0.4 0
pair_coeff * *
fix move all nve/sphere disc
fix flat all enforce2d
thermo_modify lost ignore
timestep 0.01
run {steps}
"""


def lammps(count: int, steps: int, processes: int, workdir: Path) -> float | None:
    """Particle-steps/s of Debian's LAMMPS on the same packed blob (fixed radii, contacts only:
    LAMMPS has no magnets or servo); None when `lmp` is not installed."""
    lmp = shutil.which("lmp")
    if lmp is None:
        return None
    x, y = hex_blob(count, 2 * PhysicsParams().r_min)
    span = float(np.abs(np.concatenate([x, y])).max()) + 1.0
    rows = "\n".join(
        f"{i + 1} 1 0.155 1.0 {a:.6f} {b:.6f} 0.0"
        for i, (a, b) in enumerate(zip(x, y, strict=True))
    )
    (workdir / "blob.data").write_text(
        f"blob\n\n{count} atoms\n1 atom types\n{-span} {span} xlo xhi\n{-span} {span} ylo yhi\n"
        f"-0.5 0.5 zlo zhi\n\nAtoms # sphere\n\n{rows}\n"
    )
    (workdir / "in.blob").write_text(LAMMPS_INPUT.format(steps=steps))
    command = [lmp, "-in", "in.blob", "-log", "none", "-screen", "lammps.out"]
    if processes > 1:
        command = [
            "mpirun",
            "--allow-run-as-root",
            "--oversubscribe",
            "-np",
            str(processes),
            *command,
        ]
    subprocess.run(command, cwd=workdir, check=True, capture_output=True)
    loop = re.search(r"Loop time of ([0-9.eE+-]+)", (workdir / "lammps.out").read_text())
    return count * steps / float(loop.group(1)) if loop else None


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
    parser.add_argument("--lammps", action="store_true", help="also run Debian's LAMMPS (lmp)")
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
          f" {'peak RSS MB':>11} {'rebuilds':>8} {'CPU ns/particle-step':>20}")  # fmt: skip
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
              f" {r['realtime_factor']:>11.2f} {r['peak_rss_mb']:>11.0f} {r['rebuilds']:>8}"
              f" {r['cpu_ns_per_particle_step']:>20.1f}",
              flush=True)  # fmt: skip
        if args.lammps:
            with tempfile.TemporaryDirectory() as workdir:
                for processes in (1, 2):
                    rate = lammps(count, 200, processes, Path(workdir))
                    if rate is not None:
                        print(f"{'':>10} LAMMPS gran/hooke, {processes} process(es): {rate:.3g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
