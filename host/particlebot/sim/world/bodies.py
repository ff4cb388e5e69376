"""What lives in the world besides the swarm's particles, and what a run's bodies look like."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(frozen=True)
class PassiveObject:
    """A disc the swarm may push (the published nDead = -1 object): centre and radius in metres;
    mass, friction and magnetic attraction as factors of a particle's. The published main reads
    its radius as radFactor x R_min (the scenario converts)."""

    x: float
    y: float
    radius: float
    mass_factor: float = 1.0
    friction_factor: float = 1.0
    attraction_factor: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x", "y", "radius", "mass_factor", "friction_factor", "attraction_factor"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise ValueError(f"passive object: {name} must be finite, not {value}")
        if self.radius <= 0 or self.mass_factor <= 0:
            raise ValueError("passive object: radius and mass_factor must be > 0")
        if self.friction_factor < 0 or self.attraction_factor < 0:
            raise ValueError("passive object: friction and attraction factors must be >= 0")


@dataclass(frozen=True)
class DeadParticles:
    """`count` particles of the robot, drawn from the run's seed when the simulated time first
    reaches at_s, stop actuating: their radius stays what it was (the published model). With
    `detach` they also switch their magnets off and leave the robot (Fig. S21)."""

    count: int = 0
    at_s: float = 0.0
    detach: bool = False

    def __post_init__(self) -> None:
        if isinstance(self.count, bool) or not isinstance(self.count, int) or self.count < 0:
            raise ValueError(f"dead count must be a whole number >= 0, not {self.count!r}")
        if not (math.isfinite(self.at_s) and self.at_s >= 0):
            raise ValueError(f"dead at_s must be >= 0, not {self.at_s}")


@dataclass(frozen=True)
class BodyState:
    """Every body at one moment, in the caller's particle order (copies; for outputs)."""

    t: float
    x: FloatArray
    y: FloatArray
    vx: FloatArray
    vy: FloatArray
    radius: FloatArray
    alive: BoolArray
    """False once a particle died."""
    member: BoolArray
    """Part of the robot: not a free particle waiting to be annexed, not a detached dead one."""
    free: BoolArray
    """A free particle not annexed yet."""
    acting: BoolArray
    """May actuate now (alive, member, not held still by a shadow)."""
    objects: FloatArray
    """Passive objects, one row each: x, y, vx, vy, radius."""
