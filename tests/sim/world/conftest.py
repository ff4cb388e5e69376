"""Helpers for the world's tests: a controller that commands one radius, worlds without friction."""

from __future__ import annotations

import math

import numpy as np

from particlebot.sim.particles.model.controller import Controller, FloatArray, WorldView
from particlebot.sim.world import PhysicsParams

R_MIN = PhysicsParams().r_min


def physics(
    *, friction: bool = True, magnets: bool = True, half_width: float = 64.0
) -> PhysicsParams:
    """The published parameters, optionally without ground friction or without magnets."""
    return PhysicsParams(
        mu=PhysicsParams.mu if friction else 0.0,
        attraction=PhysicsParams.attraction if magnets else 0.0,
        magnet_clamp_force=PhysicsParams.magnet_clamp_force if magnets else 0.0,
        half_width=half_width,
    )


class Command(Controller):
    """Commands the same radius to every particle every step (NaN: hold where it is)."""

    def __init__(self, radius: float = math.nan) -> None:
        self.radius = radius

    def bind(self, count: int, rng: np.random.Generator) -> None:
        pass

    def command(self, view: WorldView, out: FloatArray) -> None:
        out[:] = self.radius


def cluster(count: int, seed: int, gap: float = 0.5e-3) -> tuple[FloatArray, FloatArray]:
    """A compact hexagonal patch of contracted discs `gap` apart (no knife-edge contacts),
    jittered a little so that no two pairs are alike."""
    rng = np.random.default_rng(seed)
    spacing = 2 * R_MIN + gap
    side = math.ceil(math.sqrt(count)) + 1
    i, j = np.meshgrid(np.arange(side), np.arange(side))
    x = ((i + 0.5 * (j % 2)) * spacing).ravel()[:count]
    y = (j * spacing * math.sqrt(3) / 2).ravel()[:count]
    return x + rng.uniform(-1e-4, 1e-4, count), y + rng.uniform(-1e-4, 1e-4, count)
