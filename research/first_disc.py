#!/usr/bin/env python3
"""What the published placement's unseen first disc changes: the published code puts its first
disc at (5, 0) but files it in the grid cell of (0, 0), so the overlap test of every later disc
misses it and discs may be put down on top of it. Counts those overlaps over seeds, and runs the
dead study's cell (published-blob placement) with the first disc seen and unseen on the same seed.

    PYTHONPATH=host python research/first_disc.py --sizes 100 1000 10000 --seeds 20
    PYTHONPATH=host python research/first_disc.py --run 10000 --run-seeds 1 --duration 1h \\
        --csv data/studies/first-disc.csv
"""

from __future__ import annotations

import argparse
import csv
import functools
import math
import sys
import time
from pathlib import Path

import numpy as np

from particlebot.sim.scenarios import build, placement
from particlebot.sim.scenarios.build import PLACEMENT_STREAM
from particlebot.sim.world.params import PhysicsParams
from particlebot.studies.definitions import STUDIES, RawOptions, resolve
from particlebot.studies.runners import SimulatorRunner, execute


def overlaps(count: int, seed: int) -> tuple[int, float]:
    """Discs put down on the unseen first disc, and the deepest overlap (in radii), for the
    placement a study's run of `seed` gets."""
    radius = PhysicsParams().r_min
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(PLACEMENT_STREAM,)))
    xy = placement.algorithm5_published(count, radius, rng, first_disc_seen=False).xy
    gaps = np.hypot(*(xy[1:] - xy[0]).T) - 2 * radius
    on_top = gaps < -1e-9 * radius
    deepest = float(-gaps[on_top].min() / radius) if on_top.any() else 0.0
    return int(on_top.sum()), deepest


def paired_speed(count: int, seed: int, duration: str, skip: str) -> dict[str, float]:
    """The dead study's 0 %-dead speed (mm/s) for one seed, the first disc seen and unseen."""
    study = STUDIES["dead"]
    raw = RawOptions(
        sizes=str(count), values="0", seeds="1", first_seed=str(seed), duration=duration,
        skip=skip, placement="published-blob",
    )  # fmt: skip
    (spec,) = study.specs(resolve(study, raw))
    speeds = {}
    original, check = build.algorithm5_published, build.overlaps
    for seen in (True, False):
        build.algorithm5_published = functools.partial(original, first_disc_seen=seen)
        if not seen:
            # The world refuses overlapping discs at the start; the published code runs them
            # (its contacts push them apart), so the unseen run does too.
            build.overlaps = lambda xy, radii: None
        try:
            began = time.monotonic()
            record = execute(SimulatorRunner(), spec)
        finally:
            build.algorithm5_published, build.overlaps = original, check
        speeds["seen" if seen else "unseen"] = record.metrics["speed_mm_s"]
        print(f"  {count} particles, seed {seed}, first disc {'seen' if seen else 'unseen'}: "
              f"{record.metrics['speed_mm_s']:.4f} mm/s ({time.monotonic() - began:.0f} s)",
              flush=True)  # fmt: skip
    return speeds


def seed_range(text: str) -> range:
    """'3' or '1-3' -> the seeds, for argparse (which turns a ValueError into one line)."""
    first, _, last = text.partition("-")
    seeds = range(int(first), int(last or first) + 1)
    if not seeds or seeds.start < 0:
        raise ValueError(text)
    return seeds


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="*", default=[100, 1000, 10000])
    parser.add_argument("--seeds", type=int, default=20, help="placements counted per size")
    parser.add_argument("--run", type=int, help="also run the dead study's cell of this size")
    parser.add_argument(
        "--run-seeds", type=seed_range, default="1", help="seeds of those runs, e.g. 1-3"
    )
    parser.add_argument("--duration", default="2h")
    parser.add_argument("--skip", default="30min")
    parser.add_argument("--csv", help="append the runs' speeds to this CSV")
    args = parser.parse_args()

    print("| particles | seeds | seeds with a disc on the first | discs on it (mean, max) "
          "| deepest overlap (radii) |")  # fmt: skip
    print("| --- | ---: | ---: | --- | ---: |")
    for count in args.sizes:
        found = [overlaps(count, seed) for seed in range(1, args.seeds + 1)]
        on_top = [n for n, _ in found]
        print(f"| {count:,} | {args.seeds} | {sum(n > 0 for n in on_top)} "
              f"| {np.mean(on_top):.2f}, {max(on_top)} "
              f"| {max(d for _, d in found):.2f} |", flush=True)  # fmt: skip
    if args.run is None:
        return 0
    finite = True
    for seed in args.run_seeds:
        speeds = paired_speed(args.run, seed, args.duration, args.skip)
        finite = finite and all(math.isfinite(v) for v in speeds.values())
        if args.csv:
            path = Path(args.csv)
            new = not path.exists()
            with path.open("a", encoding="utf-8", newline="") as stream:
                writer = csv.writer(stream, lineterminator="\n")
                if new:
                    writer.writerow(["particles", "seed", "duration", "skip", "seen_mm_s",
                                     "unseen_mm_s"])  # fmt: skip
                writer.writerow([args.run, seed, args.duration, args.skip,
                                 f"{speeds['seen']:.6g}", f"{speeds['unseen']:.6g}"])  # fmt: skip
    return 0 if finite else 1


if __name__ == "__main__":
    sys.exit(main())
