"""The device-side counting sort's pieces: the prefix sum and the grid's shape."""

from __future__ import annotations

import numpy as np
import pytest
from numba import cuda

from particlebot.sim.world.cuda.swarms import PrefixSum, grid_sides
from particlebot.sim.world.params import PhysicsParams
from particlebot.sim.world.world import World
from tests.sim.world.conftest import Command


@pytest.mark.parametrize("count", [1, 5, 64, 65, 4097])
def test_the_prefix_sum_gives_every_cells_start_and_the_total(count: int) -> None:
    # 1 and 64: one tile; 65: two levels; 4097: three.
    counts = np.random.default_rng(count).integers(0, 4, count).astype(np.int32)
    out = cuda.device_array(count + 1, dtype=np.int64)
    PrefixSum(count)(cuda.to_device(counts), out)
    assert out.copy_to_host().tolist() == [0, *np.cumsum(counts).tolist()]


def test_a_small_swarm_wraps_a_large_arena_onto_a_small_grid() -> None:
    world = World([0.0], [0.0], controller=Command())
    full, side = grid_sides(world._prm, 10_000)
    reach = 2 * PhysicsParams().r_max + PhysicsParams().magnet_cutoff
    assert full == int(2 * PhysicsParams().half_width / reach) + 1  # 523: the whole arena
    assert side == 128  # a power of two near sqrt(10,000)
    assert grid_sides(world._prm, 1) == (full, 4)
