"""The kernels' fast paths against their plain forms: the vectorised pair law, pairs taken from
the grid against pairs taken from the lists."""

from __future__ import annotations

import numpy as np

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.world import Lamp, PhysicsParams, World
from particlebot.sim.world import kernels as k
from tests.sim.world.conftest import R_MIN, cluster

Law = tuple[float, float, float, float, float, float, float, float]


def _law(params: PhysicsParams) -> Law:
    return (
        params.spring, params.damping, params.shear, params.magnet_clamp_force,
        params.clamp_gap, params.blend_gap, params.attraction, 0.9e-3,
    )  # fmt: skip


def test_the_vectorised_pair_law_gives_each_pair_the_bits_it_gets_alone() -> None:
    # Overlapping, clamped, blended and far pairs, some without magnets: evaluated together
    # (vector instructions) and one at a time (scalar ones) they must agree to the last bit, so
    # that where a block of pairs ends changes nothing.
    rng = np.random.default_rng(3)
    count = 2000
    angle = rng.uniform(0, 2 * np.pi, count)
    contact = rng.uniform(2 * R_MIN, 0.235, count)
    distance = contact + rng.uniform(-0.01, 0.011, count)
    inputs = np.stack([
        distance * np.cos(angle), distance * np.sin(angle), contact,
        rng.normal(0, 0.3, count), rng.normal(0, 0.3, count), rng.choice([0.0, 1.0], count),
    ])  # fmt: skip
    law = _law(PhysicsParams())
    together = np.zeros((5, count))
    k._pair_forces(count, inputs, law, together)
    alone = np.zeros((5, count))
    for q in range(count):
        out = np.zeros((5, 1))
        k._pair_forces(1, np.ascontiguousarray(inputs[:, q : q + 1]), law, out)
        alone[:, q] = out[:, 0]
    assert np.array_equal(together, alone)
    pressed = distance < contact
    assert (together[2] > 0).sum() == pressed.sum() and (together[3] > 0).any()


def test_pairs_from_the_grid_equal_pairs_from_the_lists_bit_for_bit() -> None:
    # A step that rebuilds the lists takes its pairs straight from the grid and fills no list:
    # it must add up exactly what the lists would have given, in parallel chunks and in blocks
    # of any size.
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
        index = np.zeros((w._pair_index.shape[0], k.PAIR_INDEX_ROWS, block), dtype=np.int64)
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
    body, flags = sums["lists 1024"]
    for name, (other_body, other_flags) in sums.items():
        assert np.array_equal(body, other_body), name
        assert np.array_equal(flags, other_flags), name
    assert (body[k.B_FR] > 0).sum() > 100 and (body[k.B_FA] > 0).sum() > 100
    assert flags[k.F_JOINED].any()  # free particles touching the robot
