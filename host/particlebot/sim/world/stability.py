"""The world's explicit step, linearised for a touching hexagonal patch of discs: its spectral
radius over dashpots and shears says whether a packed swarm is stable or "boils" (and above which
speed the unstable mode outgrows what sliding friction takes off a step)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from particlebot.sim.world.params import PhysicsParams

FloatArray = npt.NDArray[np.float64]


def hexagonal_patch(rings: int, spacing: float) -> FloatArray:
    """Centres of a hexagon of touching discs `rings` deep around one: (N, 2)."""
    points = [
        ((i + 0.5 * j) * spacing, j * math.sqrt(3) / 2 * spacing)
        for i in range(-rings, rings + 1)
        for j in range(-rings, rings + 1)
        if abs(i + j) <= rings
    ]
    return np.array(points)


def step_matrix(centres: FloatArray, radius: float, params: PhysicsParams) -> FloatArray:
    """The world's step (positions by the old velocity, then forces from the new positions and the
    old velocities), linearised about rest for every touching pair: contact spring k n n^T and the
    dashpot on the whole relative velocity plus the shear on its tangential part, unit masses.
    Ground friction, magnets and the servo are left out (they are not linear)."""
    n = len(centres)
    stiffness = np.zeros((2 * n, 2 * n))
    damping = np.zeros((2 * n, 2 * n))
    eye = np.eye(2)
    for a in range(n):
        for b in range(a + 1, n):
            rel = centres[b] - centres[a]
            distance = float(np.hypot(*rel))
            if distance > 2 * radius * (1 + 1e-9):
                continue
            normal = np.outer(rel, rel) / distance**2
            blocks = (
                (stiffness, params.spring * normal),
                (damping, params.damping * eye + params.shear * (eye - normal)),
            )
            for matrix, block in blocks:  # the force on a is block (x_b - x_a); b gets its opposite
                sa, sb = slice(2 * a, 2 * a + 2), slice(2 * b, 2 * b + 2)
                matrix[sa, sa] -= block
                matrix[sa, sb] += block
                matrix[sb, sb] -= block
                matrix[sb, sa] += block
    dt = params.dt
    ident = np.eye(2 * n)
    # x' = x + dt v;  v' = v + dt (K x' + C v)
    top = np.hstack([ident, dt * ident])
    bottom = np.hstack([dt * stiffness, ident + dt * dt * stiffness + dt * damping])
    return np.vstack([top, bottom])


@dataclass(frozen=True)
class Stability:
    damping: float
    shear: float
    spectral_radius: float
    dominant: complex
    """The eigenvalue of largest modulus (negative real: a mode that flips sign every step)."""
    threshold_speed: float
    """Speed (m/s) above which that mode outgrows what sliding friction takes off a step, mu g dt
    / (radius - 1); infinite for a stable step."""


def stability(params: PhysicsParams, rings: int) -> Stability:
    centres = hexagonal_patch(rings, 2 * params.r_min)
    values = np.linalg.eigvals(step_matrix(centres, params.r_min, params))
    dominant = complex(values[np.argmax(np.abs(values))])
    rho = float(abs(dominant))
    slide = params.mu * params.gravity * params.dt
    threshold = slide / (rho - 1) if rho > 1 + 1e-6 else math.inf  # (1: rigid motions)
    return Stability(params.damping, params.shear, rho, dominant, threshold)
