"""The kernels compiled afresh and loaded from numba's cache: a seeded swarm follows the same path
either way (it once did not: fast-math pair arithmetic came out differently optimised), and a
fresh process can resume a swarm with cached kernels (it once segfaulted)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

SUBPROCESS_DEADLINE_S = 1800.0
"""Each script compiles the kernels from an empty cache: about 2.5 min on an idle 2-core machine,
up to five or ten times that on a machine at load 5-10. The deadline only catches a hang, so it
sits an order of magnitude above the typical time; a failure to compile fails at once."""

# Each test compiles the kernels in fresh processes: minutes, so in the slow tier. The tests' own
# limit replaces pytest-timeout's 300 s default (which a loaded machine reaches):
# three scripts back to back, each with its deadline.
pytestmark = [pytest.mark.slow, pytest.mark.timeout(3 * SUBPROCESS_DEADLINE_S + 60)]

# The end of a script that ran `world`: prints a digest of every particle's position, velocity
# and radius.
_DIGEST = """
import hashlib
import numpy as np

state = world.state()
digest = hashlib.sha256()
for row in (state.x, state.y, state.vx, state.vy, world.radii()):
    digest.update(np.ascontiguousarray(row).tobytes())
print(digest.hexdigest())
"""

# A packed blob large enough for the parallel path, run for a second.
_RUN = (
    """
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
"""
    + _DIGEST
)


# A small swarm (the inline path) resumed from a snapshot file as the first thing the process
# does, as `particlebot simulate --resume` does, and run 50 steps on. Without the file, makes it
# instead (50 steps, saved) and prints "made".
_RESUME = (
    """
import sys
from pathlib import Path
import numpy as np
from particlebot.sim.world import World
from particlebot.sim.world.world import Snapshot

path = Path(sys.argv[1])
if not path.exists():
    from particlebot.sim.particles.model.published import PublishedController
    from particlebot.sim.world import Lamp

    xs = np.array([0.0, 0.2, 0.4])
    made = World(xs, np.zeros(3), controller=PublishedController(), lamp=Lamp(-3.0, 0.0), seed=1)
    made.step(50)
    made.snapshot().save(path)
    print("made")
    sys.exit(0)
world = World.from_snapshot(Snapshot.load(path))
world.step(50)
"""
    + _DIGEST
)


@pytest.fixture(scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One numba cache for the module, empty at first (the second test then compiles only what
    the first did not)."""
    return tmp_path_factory.mktemp("numba-cache")


def _run(cache: Path, script: str = _RUN, *args: str) -> str:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    try:
        done = subprocess.run(
            [sys.executable, "-c", script, *args], env=env, capture_output=True, text=True,
            timeout=SUBPROCESS_DEADLINE_S,
        )  # fmt: skip
    except subprocess.TimeoutExpired:
        pytest.fail(f"the script did not end in {SUBPROCESS_DEADLINE_S:.0f} s: a hang")
    assert done.returncode == 0, f"exit {done.returncode}: {done.stderr[-2000:]}"
    return done.stdout.strip().splitlines()[-1]


def test_fresh_and_cached_kernels_give_the_same_bits(cache: Path) -> None:
    fresh = _run(cache)  # an empty cache: everything compiled in this process
    assert any(cache.rglob("*.nbc"))  # and written to the cache
    cached = _run(cache)
    assert cached == fresh


def test_a_fresh_process_resumes_a_small_swarm_from_cached_kernels(
    cache: Path, tmp_path: Path
) -> None:
    # The kernels that can reach a parallel region link against numba's scheduler, whose
    # symbols exist only once its thread pool has started. Resuming is the first kernel call
    # of `simulate --resume`, and a small swarm starts no pool on its own: restore_lists,
    # compiled in such a process and then loaded from the cache, segfaulted (exit -11).
    snapshot = tmp_path / "small.npz"
    assert _run(cache, _RESUME, str(snapshot)) == "made"
    first = _run(cache, _RESUME, str(snapshot))  # compiles what resuming needs, caches it
    again = _run(cache, _RESUME, str(snapshot))  # resumes with everything from the cache
    assert again == first
