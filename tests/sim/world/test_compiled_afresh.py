"""A seeded swarm follows the same path whether numba compiles the kernels afresh or loads them
from its cache (it once did not: fast-math pair arithmetic came out differently optimised)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

# A packed blob large enough for the parallel path, run for a second; prints a digest of every
# particle's position, velocity and radius.
_RUN = """
import hashlib
import numpy as np
from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.scenarios.placement import hexagonal
from particlebot.sim.world import Lamp, PhysicsParams, World
from particlebot.sim.world.world import PARALLEL_FROM

spacing = 2 * PhysicsParams().r_min
blob = hexagonal(PARALLEL_FROM + 1000, spacing)
controller = PublishedController()
world = World(blob.xy[:, 0], blob.xy[:, 1], controller=controller, lamp=Lamp(-30.0, 0.0), seed=1)
for _ in range(100):
    world.step(1)
state = world.state()
digest = hashlib.sha256()
for row in (state.x, state.y, state.vx, state.vy, world.radii()):
    digest.update(np.ascontiguousarray(row).tobytes())
print(digest.hexdigest())
"""


def _run(cache: Path) -> str:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    done = subprocess.run(
        [sys.executable, "-c", _RUN], env=env, capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, done.stderr
    return done.stdout.strip().splitlines()[-1]


def test_fresh_and_cached_kernels_give_the_same_bits(tmp_path: Path) -> None:
    fresh = _run(tmp_path)  # an empty cache: everything compiled in this process
    assert any(tmp_path.rglob("*.nbc"))  # and written to the cache
    cached = _run(tmp_path)
    assert cached == fresh
