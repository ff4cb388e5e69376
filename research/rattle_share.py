#!/usr/bin/env python3
"""Measures how much of an actuating swarm rattles (moves faster than 0.1 m/s) against the contact
shear and dashpot."""

from __future__ import annotations

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.scenarios.placement import algorithm5, algorithm5_published
from particlebot.sim.world import Lamp, PhysicsParams, World

FAST_M_S = 0.1
"""What counts as rattling: 10 cm a second is 1 mm a step, five times how fast the servo grows a
radius (4 cm over a 2 s rise) and 4.5 times what sliding friction takes off in a step (mu g dt =
2.2 cm/s); the wave itself moves a swarm well under 1 mm/s."""


COLUMNS = (
    "particles", "shear", "torque_limit", "rattling_share", "mean_speed_m_s", "seconds", "damping",
    "placement", "settle_s",
)  # fmt: skip

PLACEMENTS = {"blob": algorithm5, "published-blob": algorithm5_published}
"""The studies' names (`particlebot study --placement`) for SI Algorithm 5 and the published
code's sparser version of it."""


def published_swarm(count: int, params: PhysicsParams, placement: str = "blob") -> World:
    """The swarm these measurements watch: seed 1, placed as `placement` names, the published
    controller, the lamp 20 m off its -x edge (swarm_start.py watches the same one)."""
    xy = PLACEMENTS[placement](count, params.r_min, np.random.default_rng(1)).xy
    lamp = Lamp(float(xy[:, 0].min()) - 20.0, float(xy[:, 1].mean()))
    return World(xy[:, 0], xy[:, 1], controller=PublishedController(), params=params,
                 lamp=lamp, seed=1)  # fmt: skip


def measure(
    count: int, shear: float, torque_limit: float, damping: float, settle_s: float,
    window_s: float, placement: str = "blob",
) -> dict[str, float]:  # fmt: skip
    """One published_swarm: the share of particles faster than FAST_M_S and their mean speed,
    sampled every second over `window_s` after `settle_s`."""
    params = PhysicsParams(shear=shear, torque_limit=torque_limit, damping=damping)
    world = published_swarm(count, params, placement)
    world.run(settle_s)
    shares = []
    speeds = []
    for _ in range(int(window_s)):
        world.run(1.0)
        state = world.state()
        speed = np.hypot(state.vx, state.vy)
        shares.append(float(np.mean(speed > FAST_M_S)))
        speeds.append(float(speed.mean()))
    return {"rattling_share": float(np.mean(shares)), "mean_speed_m_s": float(np.mean(speeds))}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 1_000, 10_000])
    parser.add_argument(
        "--shears", type=float, nargs="+",
        default=[20, 22.5, 25, 26, 27, 27.5, 28, 28.5, 29, 30, 32.5, 35, 40],
    )  # fmt: skip
    parser.add_argument("--torque-limit", type=float, default=0.7)
    parser.add_argument("--dampings", type=float, nargs="+", default=[PhysicsParams().damping])
    parser.add_argument("--placements", choices=sorted(PLACEMENTS), nargs="+", default=["blob"])
    parser.add_argument("--settles", type=float, nargs="+", default=[300.0],
                        help="seconds before sampling (each a run of its own)")  # fmt: skip
    parser.add_argument("--window", type=float, default=120.0, help="seconds sampled")
    parser.add_argument("--out", type=Path, default=Path("data/studies/rattle-shear.csv"))
    args = parser.parse_args()
    if (min(args.sizes) < 3 or min(args.shears) < 0 or min(args.dampings) < 0
            or min(args.settles) < 0 or args.window < 1):  # fmt: skip
        print("rattle_share: needs sizes >= 3, shears and dampings >= 0, --settles >= 0, "
              "--window >= 1", file=sys.stderr)  # fmt: skip
        return 2
    rows = []
    cases = [
        (n, s, d, t, p) for n in args.sizes for s in args.shears for d in args.dampings
        for t in args.settles for p in args.placements
    ]  # fmt: skip
    for done, (count, shear, damping, settle, placement) in enumerate(cases, start=1):
        began = time.perf_counter()
        result = measure(
            count, shear, args.torque_limit, damping, settle, args.window, placement
        )  # fmt: skip
        seconds = time.perf_counter() - began
        rows.append({"particles": count, "shear": shear, "torque_limit": args.torque_limit,
                     **result, "seconds": round(seconds, 1), "damping": damping,
                     "placement": placement, "settle_s": settle})  # fmt: skip
        share = 100 * result["rattling_share"]
        case = f"{count} particles ({placement}), shear {shear:g}, damping {damping:g}, "
        case += f"after {settle:g} s"
        print(f"[{done}/{len(cases)}] {case}: {share:.3f} % rattling ({seconds:.0f} s)", flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    with args.out.open("w", newline="") as stream:
        writer = csv.DictWriter(stream, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
