"""World.place: a particle put down by hand stays where it is put, at rest, until forces move it."""

from __future__ import annotations

import numpy as np
import pytest

from particlebot.sim.particles.model.controller import Controller, FloatArray, WorldView
from particlebot.sim.world import Arena, Circle, World


class Contracted(Controller):
    """Every particle stays contracted: nothing but forces can move a body."""

    def bind(self, count: int, rng: np.random.Generator) -> None:
        pass

    def command(self, view: WorldView, out: FloatArray) -> None:
        out[:] = view.r_min


def test_a_placed_particle_stays_put_and_the_others_keep_their_places() -> None:
    world = World([0.0, 0.155, 0.31], [0.0, 0.0, 0.0], controller=Contracted())
    world.step(10)
    world.place(1, 0.5, 0.7)
    world.step(50)
    x, y = world.positions()
    assert (x[1], y[1]) == (0.5, 0.7)
    assert np.allclose([x[0], x[2]], [0.0, 0.31], atol=1e-3)


def test_particles_placed_onto_each_other_are_pushed_apart() -> None:
    world = World([0.0, 1.0], [0.0, 0.0], controller=Contracted())
    world.place(1, 0.1, 0.0)  # 55 mm into particle 0
    world.step(100)
    x, _ = world.positions()
    assert x[1] - x[0] > 0.15


@pytest.mark.parametrize(
    ("x", "y", "complaint"),
    [
        (2.0, 0.0, "obstacle"),
        (70.0, 0.0, "walls"),
        (float("nan"), 0.0, "finite"),
    ],
)
def test_a_place_in_an_obstacle_or_outside_the_walls_is_refused(
    x: float, y: float, complaint: str
) -> None:
    world = World(
        [0.0], [0.0], controller=Contracted(), arena=Arena(circles=(Circle(2.0, 0.0, 0.3),))
    )
    with pytest.raises(ValueError, match=complaint):
        world.place(0, x, y)
    assert world.positions()[0][0] == 0.0
