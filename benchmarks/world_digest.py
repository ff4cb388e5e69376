#!/usr/bin/env python3
"""Digests of the world's state after fixed runs through every kernel path, to show that a change
to the kernels leaves the bits alone: run it before and after, on one thread and on two.

    NUMBA_NUM_THREADS=1 python benchmarks/world_digest.py [boiling calm small stale f32]
    NUMBA_NUM_THREADS=2 python benchmarks/world_digest.py

boiling: a 20,000-particle blob that rebuilds its lists at almost every step (pairs from the
grid, re-ordering every SORT_EVERY-th build); calm: the same with a wide skin (pairs from the
lists); small: 1,000 particles (the inline path) with obstacles and passive objects; stale: the
published stale grid; f32: the boiling blob in float32 with a passive object. The numba cache
keys a kernel on its own file only: clear it (the __pycache__ folders beside the kernels) when
comparing a change to a module that others inline.
"""

from __future__ import annotations

import hashlib
import math
import sys
from typing import Any

import numba
import numpy as np

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.world import Arena, Circle, Lamp, PassiveObject, PhysicsParams, Rect, World
from particlebot.sim.world.params import NeighbourSearch


def hex_blob(count: int, spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """The `count` points of a hexagonal lattice (`spacing` apart) nearest the origin."""
    m = int(math.sqrt(count / 0.9) * 0.6) + 3
    i, j = np.meshgrid(np.arange(-m, m + 1), np.arange(-m, m + 1))
    x = (i + 0.5 * j).ravel() * spacing
    y = (j * math.sqrt(3) / 2).ravel() * spacing
    nearest = np.argsort(x * x + y * y, kind="stable")[:count]
    return x[nearest], y[nearest]


def digest(world: World) -> str:
    """The first 16 hex digits of a SHA-256 over positions, velocities and radii."""
    state = world.state()
    h = hashlib.sha256()
    for row in (state.x, state.y, state.vx, state.vy, world.radii()):
        h.update(np.ascontiguousarray(row).tobytes())
    return h.hexdigest()[:16]


def case(name: str, count: int, steps: int, physics: dict[str, Any], **options: Any) -> None:
    """Runs a packed blob of published controllers `steps` steps; prints its digest."""
    base = PhysicsParams()
    x, y = hex_blob(count, 2 * base.r_min)
    half = max(base.half_width, float(np.abs(np.concatenate([x, y])).max()) * 1.5 + 5)
    params = PhysicsParams(half_width=half, **physics)
    lamp = Lamp(-float(np.abs(x).max()) - 20.0, 0.0)
    world = World(
        x, y, controller=PublishedController(), params=params, lamp=lamp, seed=1, **options
    )
    # Pinned to numba's count (NUMBA_NUM_THREADS), so that a busy machine's thread choice does
    # not quietly run "two threads" on one.
    world.thread_count = numba.get_num_threads()
    world.step(steps)
    print(
        f"{name:8s} n={count} steps={steps} rebuilds={world.rebuilds} "
        f"threads={world.threads} {digest(world)}"
    )


def main() -> None:
    which = sys.argv[1:] or ["boiling", "calm", "small", "stale", "f32"]
    if "boiling" in which:
        case("boiling", 20000, 200, {})
    if "calm" in which:
        case("calm", 20000, 200, {"skin": 0.3})
    if "small" in which:
        objects = [PassiveObject(0.0, 3.3, 0.5, attraction_factor=1.0), PassiveObject(-3.5, 0, 0.3)]
        arena = Arena(rects=(Rect(3.5, 4.0, -1.0, 1.0),), circles=(Circle(0.0, -4.0, 0.4),))
        case("small", 1000, 200, {}, objects=objects, arena=arena)
    if "stale" in which:
        stale = {"neighbour_search": NeighbourSearch.PUBLISHED_STALE_GRID, "sort_interval": 0.5}
        case("stale", 500, 200, stale)
    if "f32" in which:
        case("f32", 20000, 100, {}, precision="float32", objects=[PassiveObject(0.0, 13.0, 1.0)])


if __name__ == "__main__":
    main()
