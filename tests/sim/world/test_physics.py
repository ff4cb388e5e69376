"""The world's laws one at a time: contacts, momentum, energy, friction, magnets, walls, obstacles,
the servo's stall."""

from __future__ import annotations

import math

import numpy as np
import pytest

from particlebot.sim.particles.model.published import PublishedController
from particlebot.sim.world import Arena, Circle, Lamp, PhysicsParams, Rect, World
from tests.sim.world.conftest import R_MIN, Command, cluster, physics


def test_overlapping_pair_is_pushed_apart_along_the_line_of_centres_by_the_spring() -> None:
    params = physics(friction=False, magnets=False)
    overlap = 0.004
    angle = math.radians(30)
    d = 2 * R_MIN - overlap
    x = np.array([0.0, d * math.cos(angle)])
    y = np.array([0.0, d * math.sin(angle)])
    world = World(x, y, controller=Command(), params=params)
    world.step(1)
    state = world.state()
    # One step of unit mass at rest: v = F dt, F = k x overlap, along -n on the first disc.
    speed = params.spring * overlap * params.dt
    # A handful of floating-point operations each way: a few ulps apart, 1e-12 relative is a
    # thousand ulps on any CPU (with or without fused multiply-adds).
    assert state.vx == pytest.approx([-speed * math.cos(angle), speed * math.cos(angle)], 1e-12)
    assert state.vy == pytest.approx([-speed * math.sin(angle), speed * math.sin(angle)], 1e-12)


def test_pair_forces_conserve_momentum_in_an_actuating_frictionless_swarm() -> None:
    x, y = cluster(30, seed=1)
    world = World(x, y, controller=PublishedController(), params=physics(friction=False),
                  lamp=Lamp(-5.0, 0.0), seed=2)  # fmt: skip
    world.run(20.0)
    state = world.state()
    assert np.abs(state.vx).sum() > 0.1  # it moved
    # Pair forces cancel exactly; what is left is rounding of 30 velocities (~0.01 m/s) over
    # 2,000 steps, ~N eps |v| each step: under 1e-13 m/s however the sums are ordered.
    assert abs(state.vx.sum()) < 1e-10
    assert abs(state.vy.sum()) < 1e-10


def _energy(world: World) -> float:
    """Kinetic energy plus the springs' (no magnets in the worlds that use it)."""
    s = world.state()
    xy = np.stack([s.x, s.y], axis=1)
    d = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
    overlap = np.triu(np.maximum(s.radius[:, None] + s.radius[None, :] - d, 0.0), 1)
    return float(0.5 * (s.vx**2 + s.vy**2).sum() + 0.5 * world.params.spring * (overlap**2).sum())


def test_damped_contacts_lose_energy_and_friction_brings_everything_to_rest() -> None:
    x, y = cluster(12, seed=3, gap=-0.01)  # squeezed: 1 cm overlaps store energy
    frictionless = World(x, y, controller=Command(), params=physics(friction=False, magnets=False))
    energies = []
    for _ in range(300):
        frictionless.step(1)
        energies.append(_energy(frictionless))
    # Measured after the first step: semi-implicit Euler's velocities lag its positions by half
    # a step, so the first step alone shows kinetic energy the springs have not yet paid for.
    assert max(energies[1:]) <= energies[0]
    # The dashpots took a good share before the discs flew apart (nothing slows them then).
    assert energies[-1] < 0.6 * energies[0]
    with_friction = World(x, y, controller=Command(), params=physics(magnets=False))
    with_friction.run(10.0)
    state = with_friction.state()
    assert np.all(state.vx == 0.0) and np.all(state.vy == 0.0)


@pytest.mark.parametrize(("force", "moves"), [(4.3, False), (4.6, True)])
def test_a_resting_particle_stays_put_below_twice_the_sliding_friction(
    force: float, moves: bool
) -> None:
    # The magnets' clamp is the only force: F on each disc of a pair 0.5 mm apart. The static
    # threshold is 2 mu g = 4.44 N, twice what a sliding particle loses.
    params = PhysicsParams(magnet_clamp_force=force)
    assert 2 * params.mu * params.gravity == pytest.approx(4.442, abs=1e-3)
    x = np.array([0.0, 2 * R_MIN + 0.5e-3])
    world = World(x, np.zeros(2), controller=Command(), params=params)
    world.run(1.0)
    moved = not np.array_equal(world.positions()[0], x)
    assert moved == moves


def test_magnets_hold_a_touching_pair_and_pull_a_near_one_in() -> None:
    apart = 0.05  # m/s each way: they start separating
    x = np.array([0.0, 2 * R_MIN + 0.2e-3])
    world = World(x, np.zeros(2), controller=Command(), velocity=([-apart, apart], [0.0, 0.0]))
    world.run(2.0)
    xs, _ = world.positions()
    assert xs[1] - xs[0] - 2 * R_MIN < 2e-3  # still together
    near = World(np.array([0.0, 2 * R_MIN + 3e-3]), np.zeros(2), controller=Command())
    near.run(2.0)
    xs, _ = near.positions()
    assert xs[1] - xs[0] - 2 * R_MIN < 1e-3  # pulled into contact (from 3 mm: 5.3 N > 4.44 N)


def test_walls_reflect_a_particle_and_keep_it_inside() -> None:
    params = physics(friction=False, half_width=2.0)
    world = World([1.5], [0.0], controller=Command(), params=params, velocity=([3.0], [0.0]))
    farthest = 0.0
    for _ in range(50):
        world.step(1)
        farthest = max(farthest, float(world.positions()[0][0]))
    assert farthest <= 2.0 - R_MIN
    assert world.state().vx[0] == pytest.approx(-3.0)


@pytest.mark.parametrize(
    "arena",
    [
        Arena(rects=(Rect(1.0, 1.02, -1.0, 1.0),)),  # a thin wall across the path
        Arena(circles=(Circle(1.3, 0.05, 0.2),)),
    ],
)
def test_a_disc_shot_at_an_obstacle_never_passes_through(arena: Arena) -> None:
    world = World([0.0], [0.0], controller=Command(), params=physics(friction=False),
                  arena=arena, velocity=([2.0], [0.0]))  # fmt: skip
    for _ in range(200):
        world.step(1)
        x, y = world.positions()
        assert not arena.overlapping(x, y, np.zeros(1))[0]  # the centre is never inside
        assert x[0] < 1.1  # never beyond
    assert world.state().vx[0] < 0  # bounced back


def test_the_servo_stalls_when_wedged_between_fixed_obstacles() -> None:
    # Two posts just touching a contracted disc on either side: commanded to r_max, it grows
    # only until the posts push back with the stall torque / r.
    gap = 0.3
    arena = Arena(
        circles=(Circle(-gap / 2 - R_MIN, 0.0, gap / 2), Circle(gap / 2 + R_MIN, 0.0, gap / 2))
    )
    params = PhysicsParams()
    world = World([0.0], [0.0], controller=Command(params.r_max), arena=arena)
    world.run(3.0)
    grown = float(world.radii()[0])
    world.run(1.0)
    assert float(world.radii()[0]) == grown  # stalled
    # Each post pushes 2 k x overlap; the servo stops where the sum reaches C / r.
    overlap = grown - R_MIN
    push = 2 * 2 * params.spring * overlap
    assert push == pytest.approx(params.torque_limit / grown, rel=0.05)
    free = World([0.0], [0.0], controller=Command(params.r_max))
    free.run(3.0)
    assert float(free.radii()[0]) == pytest.approx(params.r_max)
