"""The kernels' parallel path against plain forms: pairs taken from the grid against pairs taken
from the lists, a small swarm run on it against the numpy transcription."""

from __future__ import annotations

import numpy as np
import pytest

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.world import Lamp, PhysicsParams, World
from particlebot.sim.world import kernels as k
from particlebot.sim.world import world as world_module
from particlebot.sim.world.kernels import binning, lists, step
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
    ncx, ncy, _, start, members = lists._prepare(
        w._pos, w._ref, w._vel, w._body, w._flags, w._ext, w._bounds, w._prm, True, w.threads,
        w._prm[k.P_LIST_RADIUS],
    )  # fmt: skip
    w._flags[k.F_KIND, ::20] = k.FREE  # some to be annexed when they touch the robot
    sums = {}
    for block in (k.PAIR_BLOCK, 37):
        index = np.zeros((w._pair_index.shape[0], k.PAIR_INDEX_ROWS, 2 * block), dtype=np.int64)
        values = np.zeros((w._pair_values.shape[0], k.PAIR_VALUE_ROWS, block))
        body, flags = w._body.copy(), w._flags.copy()
        for parity in (0, 1):
            step._pairs_cells_chunks(w._bounds, parity, w._pos, w._vel, body, flags, members,
                                  start, ncx, ncy, index, values, w._prm)  # fmt: skip
        sums[f"grid {block}"] = (body, flags)
        nbr = lists._lists_from_ref(w._ref, w._nbr, w._ncount, w._bounds, w._prm)
        body, flags = w._body.copy(), w._flags.copy()
        for parity in (0, 1):
            step._pairs_chunks(w._bounds, parity, w._pos, w._vel, body, flags, nbr, w._ncount,
                            index, values, w._prm)  # fmt: skip
        sums[f"lists {block}"] = (body, flags)
    for block in (k.PAIR_BLOCK, 37):
        body, flags = sums[f"lists {block}"]
        assert np.array_equal(body, sums[f"grid {block}"][0]), block
        assert np.array_equal(flags, sums[f"grid {block}"][1]), block
    # Blocks of 37 pairs add a particle's dozen-odd forces in another order than whole blocks:
    # a few ulps apart (rtol 1e-12 is a thousand ulps), 1e-9 N absolute for sums near zero.
    assert np.allclose(sums["grid 37"][0], body, rtol=1e-12, atol=1e-9)
    assert (body[k.B_FR] > 0).sum() > 100 and (body[k.B_FA] > 0).sum() > 100
    assert flags[k.F_JOINED].any()  # free particles touching the robot


@pytest.mark.slow
def test_pairs_reached_through_the_grids_order_equal_pairs_after_re_ordering() -> None:
    # Between re-orderings a boiling swarm's pair pass reaches the particles through the grid's
    # order (members) wherever they are stored: from any storage order it must add up exactly
    # what the same particles put in cell order give, particle for particle.
    x, y = cluster(2500, seed=3, gap=2e-3)
    rng = np.random.default_rng(3)
    world = World(x, y, controller=PublishedController(), lamp=Lamp(-4.0, 0.0), seed=3,
                  velocity=(rng.normal(0, 0.2, x.size), rng.normal(0, 0.2, x.size)))  # fmt: skip
    assert world._bounds.shape[0] > 2  # parallel chunks
    world.step(20)
    w = world
    shuffle = rng.permutation(x.size)  # stored in no useful order at all
    sums = {}
    for sort in (False, True):
        pos, ref, vel = w._pos[:, shuffle], w._ref[:, shuffle], w._vel[:, shuffle]
        body, flags, ext = w._body[:, shuffle], w._flags[:, shuffle], w._ext[shuffle]
        bounds = w._bounds.copy()
        ncx, ncy, _, start, members = lists._prepare(
            pos, ref, vel, body, flags, ext, bounds, w._prm, sort, w.threads,
            w._prm[k.P_LIST_RADIUS] - w._prm[k.P_SKIN],
        )  # fmt: skip
        assert np.array_equal(members, np.arange(x.size)) == sort
        body[[k.B_FR, k.B_FA, k.B_FX, k.B_FY]] = 0.0  # (the same)
        for parity in (0, 1):
            step._pairs_cells_chunks(bounds, parity, pos, vel, body, flags, members, start,
                                  ncx, ncy, w._pair_index, w._pair_values, w._prm)  # fmt: skip
        by_particle = np.empty_like(body)
        by_particle[:, ext] = body  # row e: particle e's, wherever it was stored
        sums[sort] = by_particle
    assert np.array_equal(sums[False], sums[True])
    assert (sums[True][k.B_FR] > 0).sum() > 100 and (sums[True][k.B_FA] > 0).sum() > 100


@pytest.mark.slow
@pytest.mark.parametrize("skin", [PhysicsParams.skin, 1e-6])
def test_the_parallel_path_follows_the_plain_numpy_transcription_too(
    monkeypatch: pytest.MonkeyPatch, skin: float
) -> None:
    # Small swarms run their pairs one at a time; the parallel chunks, the pairs from the grid
    # and the vectorised law are what large swarms run: made to run a small swarm here, they
    # must follow the numpy transcription of the published step as closely. A tiny skin
    # rebuilds the lists at every step, as in a boiling swarm: the particles are re-ordered
    # only at every SORT_EVERY-th build and reached through the grid's order in between.
    monkeypatch.setattr(world_module, "PARALLEL_FROM", 1)
    x, y = cluster(12, seed=9)
    controller = PublishedController()
    world = World(x, y, controller=controller, lamp=Lamp(-4.0, 0.5), seed=9,
                  params=PhysicsParams(skin=skin))  # fmt: skip
    assert world._bounds.shape[0] > 2
    worst, reference = lockstep(world, controller, steps=600)
    # Tolerance: the kernels contract a*b+c into fused multiply-adds where the CPU has them and
    # re-associate sums (fastmath contract/reassoc), numpy does neither: each step differs by a
    # few ulps of a position (1e-16 m scale), and a 10-particle cluster's contacts do not amplify
    # that in 600 steps (4e-16 m apart at the end on an AVX2 CPU). 1e-9 m catches a wrong law or
    # a missed pair (either moves a particle by micrometres within a few steps) on any CPU.
    assert np.abs(world.radii() - reference.r).max() < 1e-9
    assert worst < 1e-9
    assert world.rebuilds > 1 and np.abs(world.state().vx).max() > 0  # and something happened
    if skin < 1e-3:
        assert world.rebuilds > 500  # nearly every step (not while all rest)


@pytest.mark.parametrize("splits", [1, 2, 3, 7])
def test_binning_and_reordering_in_parts_equal_the_serial_passes(splits: int) -> None:
    # Large swarms on several threads bin and re-order in parts: the grid, the stable order
    # within each cell and every re-ordered row must be exactly the serial passes', or results
    # would depend on the number of threads. Particles sharing cells, and some sharing a place.
    rng = np.random.default_rng(splits)
    n = 3001
    pos = np.stack([rng.uniform(-3.0, 5.0, n), rng.uniform(-2.0, 1.0, n)])
    pos[:, 100:140] = pos[:, 7:8]  # 41 particles in one place
    radius = 0.265
    serial = binning._grid(pos, radius)
    parts = binning._grid_split(pos, radius, splits)
    assert serial[:2] == parts[:2]
    for a, b in zip(serial[2:], parts[2:], strict=True):
        assert np.array_equal(a, b)
    order = serial[4]
    assert not np.array_equal(order, np.arange(n))

    # Rows with values that tell slots apart: pos, ref, vel, body, flags, ext.
    vel = rng.normal(size=(2, n))
    body = rng.normal(size=(k.BODY_ROWS, n))
    flags = rng.integers(0, 255, (k.FLAG_ROWS, n), np.uint8)
    ext = rng.permutation(n).astype(np.int64)
    plain = (pos.copy(), np.zeros((2, n)), vel.copy(), body.copy(), flags.copy(), ext.copy())
    binning._reorder(order, *plain)
    split = (pos.copy(), np.zeros((2, n)), vel.copy(), body.copy(), flags.copy(), ext.copy())
    cells = binning._reorder_split(order, serial[2], *split, splits)
    for a, b in zip(plain, split, strict=True):
        if a.shape[0] == k.BODY_ROWS:  # the force rows are a step's own: not carried
            a, b = a[: binning.BODY_KEPT], b[: binning.BODY_KEPT]
        assert np.array_equal(a, b)
    assert np.array_equal(cells, serial[2][order])
    assert np.all(np.diff(cells) >= 0)  # in cell order
