"""The published code's stale neighbour search (NeighbourSearch.PUBLISHED_STALE_GRID): what it
misses after particles drift from the cells they were listed in, and what re-listing restores."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.scenarios.placement import algorithm5
from particlebot.sim.world import Lamp, PhysicsParams, Snapshot, World
from particlebot.sim.world.params import NeighbourSearch
from tests.sim.world.conftest import R_MIN, Command

CELL = 2 * PhysicsParams().r_max
STALE = NeighbourSearch.PUBLISHED_STALE_GRID


def _shot(search: NeighbourSearch, sort_interval: float = 180.0) -> World:
    """A disc at rest in the middle of its grid cell, and one listed three cells to its right
    shot at it at 2.5 m/s: it arrives after drifting ~2.3 cells from where it was listed."""
    resting = -64.0 + 272.5 * CELL  # the middle of grid column 272
    x = np.array([resting, resting + 3 * CELL])
    params = PhysicsParams(neighbour_search=search, sort_interval=sort_interval)
    return World(x, np.zeros(2), controller=Command(), params=params,
                 velocity=(np.array([0.0, -2.5]), np.zeros(2)))  # fmt: skip


@pytest.mark.slow
def test_a_pair_that_drifted_from_its_listing_is_felt_by_one_side_only() -> None:
    exact = _shot(NeighbourSearch.EXACT)
    stale = _shot(STALE)
    start = exact.positions()[0]
    exact.run(1.0)
    stale.run(1.0)
    assert stale.rebuilds == 1  # listed once, at t = 0
    # Exact: the shot disc hits the resting one and pushes it some centimetres to the left.
    assert exact.positions()[0][0] < start[0] - 0.01
    # Stale: the resting disc looks for particles listed within two cells of it and the shot
    # one was listed three cells away: it never feels the hit. The shot disc (now within two
    # cells of the resting one's listing) feels it and bounces back.
    x = stale.positions()[0]
    assert x[0] == start[0]
    assert x[1] > exact.positions()[0][1] + 0.05
    # One-sided: the pair's push is not matched, so momentum is not conserved.
    state = stale.state()
    assert state.vx[0] == 0.0


def test_re_listing_every_step_sees_every_pair_as_the_exact_search_does() -> None:
    exact = _shot(NeighbourSearch.EXACT)
    every_step = _shot(STALE, sort_interval=PhysicsParams().dt)
    exact.run(1.0)
    every_step.run(1.0)
    assert every_step.rebuilds == 100
    # The same pairs summed in another order: ulps per step, far below 1e-9 m after 100 steps.
    np.testing.assert_allclose(every_step.positions(), exact.positions(), rtol=0, atol=1e-9)


def test_a_fresh_listing_gives_the_exact_search_s_forces_in_a_swarm() -> None:
    # Right after the listing at t = 0 nothing has drifted: one step of an actuating blob is the
    # exact search's step (the pair sums in another order).
    xy = algorithm5(40, R_MIN, np.random.default_rng(5)).xy
    worlds = []
    for search in (NeighbourSearch.EXACT, STALE):
        params = PhysicsParams(neighbour_search=search)
        worlds.append(World(xy[:, 0], xy[:, 1], controller=PublishedController(), params=params,
                            lamp=Lamp(-10.0, 0.0), seed=5))  # fmt: skip
    for world in worlds:
        world.run(2.0)
    exact, stale = (w.state() for w in worlds)
    assert np.abs(exact.vx).max() > 1e-3  # it moves
    np.testing.assert_allclose(stale.vx, exact.vx, rtol=0, atol=1e-9)
    np.testing.assert_allclose(stale.x, exact.x, rtol=0, atol=1e-11)


def test_a_stale_grid_run_resumes_from_a_snapshot_bit_for_bit(tmp_path: Path) -> None:
    xy = algorithm5(12, R_MIN, np.random.default_rng(2)).xy
    params = PhysicsParams(neighbour_search=STALE, sort_interval=30.0)

    def world() -> World:
        return World(xy[:, 0], xy[:, 1], controller=PublishedController(), params=params,
                     lamp=Lamp(-10.0, 0.0), seed=2)  # fmt: skip

    whole = world()
    whole.run(100.0)
    first = world()
    first.run(45.0)  # between two listings: the resumed run must keep the old one
    first.snapshot().save(tmp_path / "s.npz")
    resumed = World.from_snapshot(Snapshot.load(tmp_path / "s.npz"))
    resumed.run(55.0)
    assert np.array_equal(resumed.state().x, whole.state().x)
    assert np.array_equal(resumed.state().vy, whole.state().vy)


@pytest.mark.parametrize("interval", [0.0, 0.001, float("nan")])
def test_a_sort_interval_below_one_step_is_refused(interval: float) -> None:
    with pytest.raises(ValueError, match="sort_interval"):
        PhysicsParams(sort_interval=interval)


def test_a_particle_put_down_by_hand_is_listed_where_it_lies() -> None:
    # place() re-orders the particles: the stale listing must follow them, and list the moved
    # one where it now lies, so that a disc put down touching another is pushed away at once.
    x = np.array([0.0, 3.0, 6.0])
    world = World(x, np.zeros(3), controller=Command(),
                  params=PhysicsParams(neighbour_search=STALE))  # fmt: skip
    world.step(1)
    world.place(2, 2 * R_MIN - 0.008, 0.0)  # 8 mm into particle 0: 8 N beats static friction
    world.step(1)
    vx = world.state().vx
    assert vx[2] > 0.0 and vx[0] < 0.0
    assert vx[1] == 0.0
