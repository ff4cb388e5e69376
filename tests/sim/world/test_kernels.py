"""The kernels' parallel path against plain forms: pairs taken from the grid against pairs taken
from the lists, a small swarm run on it against the numpy transcription."""

from __future__ import annotations

import numpy as np
import pytest

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.world import Lamp, World
from particlebot.sim.world import kernels as k
from particlebot.sim.world import world as world_module
from tests.sim.world.conftest import R_MIN, cluster
from tests.sim.world.reference import lockstep


def test_pairs_from_the_grid_equal_pairs_from_the_lists_bit_for_bit() -> None:
    # A step that rebuilds the lists takes its pairs straight from the grid and fills no list:
    # it must add up exactly what the lists would have given, in parallel chunks, with blocks
    # of pairs of any size (37: many blocks ending anywhere, particles' pairs split).
    x, y = cluster(2500, seed=5, gap=2e-3)
    rng = np.random.default_rng(5)
    radius = rng.uniform(R_MIN, R_MIN + 0.004, x.size)
    world = World(x, y, controller=PublishedController(), lamp=Lamp(-4.0, 0.0), radius=radius,
                  velocity=(rng.normal(0, 0.2, x.size), rng.normal(0, 0.2, x.size)),
                  seed=5)  # fmt: skip
    assert world._bounds.shape[0] > 2  # parallel chunks
    world.step(20)
    w = world
    ncx, ncy, cells, start = k._prepare(
        w._pos, w._ref, w._vel, w._vel_old, w._body, w._flags, w._ext, w._bounds, w._prm, True
    )
    w._flags[k.F_KIND, ::20] = k.FREE  # some to be annexed when they touch the robot
    sums = {}
    for block in (k.PAIR_BLOCK, 37):
        index = np.zeros((w._pair_index.shape[0], k.PAIR_INDEX_ROWS, 2 * block), dtype=np.int64)
        values = np.zeros((w._pair_values.shape[0], k.PAIR_VALUE_ROWS, block))
        body, flags = w._body.copy(), w._flags.copy()
        for parity in (0, 1):
            k._pairs_cells_chunks(w._bounds, parity, w._pos, w._vel_old, body, flags, cells,
                                  start, ncx, ncy, index, values, w._prm)  # fmt: skip
        sums[f"grid {block}"] = (body, flags)
        nbr = k._lists_from_ref(w._ref, w._nbr, w._ncount, w._bounds, w._prm)
        body, flags = w._body.copy(), w._flags.copy()
        for parity in (0, 1):
            k._pairs_chunks(w._bounds, parity, w._pos, w._vel_old, body, flags, nbr, w._ncount,
                            index, values, w._prm)  # fmt: skip
        sums[f"lists {block}"] = (body, flags)
    for block in (k.PAIR_BLOCK, 37):
        body, flags = sums[f"lists {block}"]
        assert np.array_equal(body, sums[f"grid {block}"][0]), block
        assert np.array_equal(flags, sums[f"grid {block}"][1]), block
    assert np.allclose(sums["grid 37"][0], body, rtol=1e-12, atol=1e-9)
    assert (body[k.B_FR] > 0).sum() > 100 and (body[k.B_FA] > 0).sum() > 100
    assert flags[k.F_JOINED].any()  # free particles touching the robot


def test_the_parallel_path_follows_the_plain_numpy_transcription_too(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Small swarms run their pairs one at a time; the parallel chunks, the pairs from the grid
    # and the vectorised law are what large swarms run: made to run a small swarm here, they
    # must follow the numpy transcription of the published step as closely.
    monkeypatch.setattr(world_module, "PARALLEL_FROM", 1)
    x, y = cluster(12, seed=9)
    controller = PublishedController()
    world = World(x, y, controller=controller, lamp=Lamp(-4.0, 0.5), seed=9)
    assert world._bounds.shape[0] > 2
    worst, reference = lockstep(world, controller, steps=600)
    assert np.abs(world.radii() - reference.r).max() < 1e-9
    assert worst < 1e-9
    assert world.rebuilds > 1 and np.abs(world.state().vx).max() > 0  # and something happened
