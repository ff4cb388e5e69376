#!/usr/bin/env python3
"""How a swarm's packing and speed evolve over a run, from its run folders' snapshots and CSV."""

from __future__ import annotations

import argparse
import csv
import math
import sys
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from particlebot.sim.runs.simcsv import read_published_csv
from particlebot.sim.scenarios.toml_file import read_scenario
from particlebot.sim.world.world import Snapshot, World

TOUCH_GAP_M = 2e-3
"""Two particles closer than their radii plus this count as touching: a little over the magnets'
1.9 mm blend, so a pair the magnets hold counts, a pair with a visible gap does not."""
INNER_SHARE = 0.5
"""The packing is measured inside a disc this share of the swarm's RMS radius round its
centroid: deep enough to leave out the ragged edge, wide enough to hold ~1/8 of the swarm."""

COLUMNS = (
    "run",
    "particles",
    "placement",
    "shear",
    "torque_limit",
    "minute",
    "inner_packing",
    "touching_neighbours",
    "share_touching_at_most_one",
    "speed_mm_s_since_last",
)


def describe(world: World) -> tuple[float, float, float]:
    """The packing fraction inside the inner disc (the particles' own areas at their radii now),
    the mean number of touching neighbours, and the share touching at most one."""
    x, y = world.positions()
    r = world.radii()
    centre_x, centre_y = float(x.mean()), float(y.mean())
    from_centre = np.hypot(x - centre_x, y - centre_y)
    inner_radius = INNER_SHARE * math.sqrt(float((from_centre**2).mean()))
    inner = from_centre < inner_radius
    packing = float(np.sum(np.pi * r[inner] ** 2) / (np.pi * inner_radius**2))
    xy = np.column_stack((x, y))
    pairs = cKDTree(xy).query_pairs(2 * float(r.max()) + TOUCH_GAP_M, output_type="ndarray")
    gap = np.hypot(*(xy[pairs[:, 0]] - xy[pairs[:, 1]]).T) - r[pairs[:, 0]] - r[pairs[:, 1]]
    touching = pairs[gap < TOUCH_GAP_M]
    counts = np.bincount(touching.ravel(), minlength=len(x))
    return packing, float(counts.mean()), float((counts <= 1).mean())


def run_rows(folder: Path) -> list[dict[str, object]]:
    """One row per snapshot of a run folder, with the speed toward the lamp (from the CSV's
    distance column) since the snapshot before."""
    scenario = read_scenario(folder / "scenario.toml")
    track = read_published_csv(folder / "run.csv")
    if track.distance_m is None:
        raise ValueError(f"{folder / 'run.csv'} has no Distance column")
    rows: list[dict[str, object]] = []
    before: tuple[float, float] | None = None
    for path in sorted((folder / "snapshots").glob("step-*.npz")):
        world = World.from_snapshot(Snapshot.load(path))
        packing, neighbours, loose = describe(world)
        distance = float(np.interp(world.t, track.time_s, track.distance_m))
        speed = math.nan
        if before is not None and world.t > before[0]:
            speed = 1000 * (before[1] - distance) / (world.t - before[0])
        before = (world.t, distance)
        rows.append(
            {
                "run": folder.name,
                "particles": world.count,
                "placement": str(scenario.swarm.placement),
                "shear": scenario.physics.shear,
                "torque_limit": scenario.physics.torque_limit,
                "minute": round(world.t / 60, 3),
                "inner_packing": round(packing, 4),
                "touching_neighbours": round(neighbours, 3),
                "share_touching_at_most_one": round(loose, 4),
                "speed_mm_s_since_last": round(speed, 4),
            }
        )
        print(f"{folder.name} {world.t / 60:6.1f} min  packing {packing:.3f}", file=sys.stderr)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("folders", type=Path, nargs="+", help="run folders (with snapshots/)")
    parser.add_argument("--out", type=Path, required=True, help="the CSV to write")
    args = parser.parse_args()
    for folder in args.folders:
        if not (folder / "scenario.toml").is_file() or not (folder / "run.csv").is_file():
            sys.exit(f"swarm_packing: {folder} is not a run folder (no scenario.toml or run.csv)")
        if not any((folder / "snapshots").glob("step-*.npz")):
            sys.exit(f"swarm_packing: {folder} has no snapshots")
    try:
        rows = [row for folder in args.folders for row in run_rows(folder)]
    except ValueError as exc:  # a run CSV without its Distance column, a scenario it cannot read
        sys.exit(f"swarm_packing: {exc}")
    with args.out.open("w", newline="") as stream:
        writer = csv.DictWriter(stream, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    print(args.out)


if __name__ == "__main__":
    main()
