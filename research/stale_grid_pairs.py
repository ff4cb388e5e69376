#!/usr/bin/env python3
"""Counts the touching pairs the published code's stale neighbour search misses (one side blind,
or both) in swarms walking toward the light, for its 180 s re-listing and a staler one."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.scenarios.placement import algorithm5
from particlebot.sim.world import Lamp, PhysicsParams, World
from particlebot.sim.world.kernels import STALE_GRID, STALE_REACH
from particlebot.sim.world.params import NeighbourSearch
from particlebot.studies.definitions import FAR_LAMP_M
from particlebot.studies.packing import densest_packing_diameter_m

TOUCH_GAP = 0.01
"""Pairs closer than this gap (m) count: the pairs our magnet cutoff keeps."""


def cells(x: np.ndarray, y: np.ndarray, params: PhysicsParams) -> tuple[np.ndarray, np.ndarray]:
    """The published grid's unwrapped column and row of each centre."""
    size = 2 * params.r_max
    origin = -params.half_width
    return np.floor((x - origin) / size).astype(int), np.floor((y - origin) / size).astype(int)


def sees(now: tuple[np.ndarray, np.ndarray], listed: tuple[np.ndarray, np.ndarray],
         a: np.ndarray, b: np.ndarray) -> np.ndarray:  # fmt: skip
    """Whether particle a, in its cell now, finds b where b was listed (the wrapped 5 x 5)."""
    half = STALE_GRID // 2
    dx = (listed[0][b] - now[0][a] + half) % STALE_GRID - half
    dy = (listed[1][b] - now[1][a] + half) % STALE_GRID - half
    return (np.abs(dx) <= STALE_REACH) & (np.abs(dy) <= STALE_REACH)


def blind_pairs(
    count: int, seed: int, sort_s: float, duration: float, every: float
) -> tuple[int, int, int]:
    """Touching pairs sampled every `every` s of a run: how many, how many one side did not
    see, how many neither side saw."""
    params = PhysicsParams(
        neighbour_search=NeighbourSearch.PUBLISHED_STALE_GRID, magnet_cutoff=1.0,
        sort_interval=sort_s,
    )  # fmt: skip
    xy = algorithm5(count, params.r_min, np.random.default_rng(seed)).xy
    lamp = Lamp(-(densest_packing_diameter_m(count) / 2 + FAR_LAMP_M), 0.0)
    world = World(xy[:, 0], xy[:, 1], controller=PublishedController(), params=params,
                  lamp=lamp, seed=seed)  # fmt: skip
    sort_steps = round(sort_s / params.dt)
    sample_steps = round(every / params.dt)
    listed = cells(xy[:, 0], xy[:, 1], params)
    total = one = both = 0
    step = 0
    while step < round(duration / params.dt):
        # The listing is made in the step whose number is a multiple of sort_steps, from the
        # positions that step moved to: the positions after it (counted from 1: k sort_steps + 1).
        next_listing = ((step - 1) // sort_steps + 1) * sort_steps + 1
        next_sample = (step // sample_steps + 1) * sample_steps
        world.step(min(next_listing, next_sample) - step)
        step = world.steps
        x, y = world.positions()
        if step % sort_steps == 1 % sort_steps:
            listed = cells(x, y, params)
        if step % sample_steps:
            continue
        r = world.radii()
        d = np.hypot(x[:, None] - x[None, :], y[:, None] - y[None, :])
        a, b = np.nonzero(np.triu(d < r[:, None] + r[None, :] + TOUCH_GAP, 1))
        now = cells(x, y, params)
        ab = sees(now, listed, a, b)
        ba = sees(now, listed, b, a)
        total += a.size
        one += int(np.count_nonzero(ab ^ ba))
        both += int(np.count_nonzero(~ab & ~ba))
    return total, one, both


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100])
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--duration", type=float, default=7200.0, help="simulated s")
    parser.add_argument("--every", type=float, default=30.0, help="sampled every (s)")
    parser.add_argument("--sorts", type=float, nargs="+", default=[180.0, 1800.0],
                        help="re-listing intervals (s)")  # fmt: skip
    args = parser.parse_args()
    if min(args.sizes) < 2 or args.seeds < 1 or args.every < 0.01 or args.duration < args.every:
        parser.error("need sizes >= 2, seeds >= 1 and 0.01 <= --every <= --duration")
    if min(args.sorts) < 0.01:
        parser.error("--sorts must be at least one step (0.01 s)")
    for count in args.sizes:
        for sort_s in args.sorts:
            total = one = both = 0
            for seed in range(args.seeds):
                t, o, b = blind_pairs(count, seed, sort_s, args.duration, args.every)
                total, one, both = total + t, one + o, both + b
            print(f"{count} particles, re-listed every {sort_s:g} s: {total} touching pairs "
                  f"sampled, one side blind {one / total:.2%}, both {both / total:.2%}",
                  flush=True)  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
