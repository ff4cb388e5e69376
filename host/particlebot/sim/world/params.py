"""The world's physical constants: the published simulator's numbers as defaults, in one place."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from enum import Enum

from particlebot.options import Bounds, check_fields

# Units throughout the world: metres, seconds, and particle masses of 1 (a force is an
# acceleration of a particle).

ATTRACTION_FITTED = 1.5884e-5
"""A of F = A / gap^2 (N m^2) as the published model fits it: 4.4 N at a 1.9 mm gap, close to the
4.5 N peak adhesion of SI S7. The published main multiplies it by 3 for its studies."""


BYTES_PER_PARTICLE = 1024
"""Memory a world holds per particle, with room: a 100,000-particle world peaks at 510 B a
particle while built and stepped (tracemalloc), the pictures and CSV rows take some more."""
BYTES_FIXED = 64 << 20
"""Memory a world holds whatever its size (buffers, the compiled kernels)."""
MAGNITUDE_LIMIT = 1e9
"""No number of the model reaches this in a real swarm (the largest, the contact spring, is
10^3); beyond it a product of two of them leaves the range the kernels compute in."""
RANGES = {
    "dt": Bounds(minimum=1e-6, maximum=1.0),
    "r_min": Bounds(above=0, maximum=10.0),
    "r_max": Bounds(above=0, maximum=10.0),
    "half_width": Bounds(above=0, maximum=1e4),
}
"""Fields narrower than [0, MAGNITUDE_LIMIT]: a step of a microsecond to a second, bodies up to
10 m across, walls up to 10 km out."""
STABLE = 2.0
"""The explicit integration of a contact spring k and a dashpot c stays bounded while
dt sqrt(k) < 2 and dt c < 2; the published 0.01 s, k = 1000 and c = 10 + 40 give 0.32 and 0.5."""


class NeighbourSearch(Enum):
    """How a particle finds the particles it interacts with."""

    EXACT = "exact"
    """Ours: every pair within reach, from neighbour lists kept up to date (the default)."""
    PUBLISHED_STALE_GRID = "published-stale-grid"
    """The published code's search, for measuring what it changes (slow, for small swarms): the
    particles are listed in a 512 x 512 wrapping grid of 2 r_max cells (origin at -half_width)
    every sort_interval; each step a particle meets every particle LISTED in the 5 x 5 cells
    around its CURRENT cell, so a pair goes unseen from one side once the other has drifted two
    cells from where it was listed, until the next sort. One-sided, as published: i can feel j
    while j does not feel i. Serial; passive objects still meet every particle directly;
    `World.rebuilds` counts the listings."""


@dataclass(frozen=True)
class PhysicsParams:
    """Every number of the published model (richa-batra/ParticleRobotSimulations, read as facts),
    plus the few of our own, each marked as a deviation where the published model has none."""

    dt: float = 0.01
    """Time step (s); semi-implicit Euler, positions first."""
    r_min: float = 0.0775
    """Contracted radius (m)."""
    r_max: float = 0.1175
    """Fully expanded radius (m)."""

    spring: float = 1000.0
    """Contact stiffness k (N/m per unit mass): force k x overlap along the line of centres."""
    damping: float = 10.0
    """Contact dashpot on the WHOLE relative velocity (1/s), as published (not its normal part)."""
    shear: float = 40.0
    """Extra damping of the tangential relative velocity in contact (1/s)."""
    obstacle_spring_factor: float = 2.0
    """Obstacles push back with this x spring (the published 2k)."""

    attraction: float = 3 * ATTRACTION_FITTED
    """A of F = A / gap^2 (N m^2): the published main's 3 x the fitted value."""
    magnet_clamp_force: float = 2.5
    """Magnet force (N) below clamp_gap: the published clamp against F -> infinity at contact."""
    clamp_gap: float = 0.9e-3
    """Gap (m) below which the magnet force is the clamp."""
    blend_gap: float = 1.9e-3
    """Gap (m) where the linear blend from the clamp reaches A / gap^2."""
    magnet_cutoff: float = 0.01
    """DEVIATION: magnets act only across gaps below this (m); beyond it their pull is under
    0.48 N, a ninth of what moves a resting particle. The published code reaches every particle
    in a 5 x 5 block of cells 2 R_max wide (0.47-0.7 m, not isotropic). Measured (README): 0.01,
    0.05 and 0.6 m give the same speeds toward the light for 10 and 100 particles; 1,000 and
    10,000 particles go 12-19 % faster uncut, nearly all of it from pulls across 1-5 cm."""

    mu: float = 0.4
    """Ground friction coefficient."""
    gravity: float = 9.81 * 0.566
    """Effective g (m/s^2) of the friction law: the published 9.81 x 0.566."""
    static_factor: float = 2.0
    """A particle at rest stays put while |F| < static_factor x mu x g (the published 2)."""
    rest_speed: float = 1e-6
    """Below this speed (m/s) a particle counts as at rest for static friction."""

    max_speed: float = 0.1
    """Servo: growth per step is capped at max_speed x r_max / r x dt (m)."""
    torque_limit: float = 0.5
    """Servo: the stall torque C; growth stops when the contact-force sum reaches C / r."""
    constrain_contraction: bool = False
    """Servo: contraction resisted by the magnets' pull (published option, off by default)."""
    contraction_coefficient: float = 10.0
    """Servo: Cc of the constrained contraction."""

    half_width: float = 64.0
    """Reflective walls at +-half_width (m), the published world."""

    skin: float = 0.02
    """Neighbour lists (ours): pairs within 2 r_max + magnet_cutoff + skin are listed, and the
    list is rebuilt when a body has moved skin / 2 since the last build. No effect on results
    beyond the order of floating-point sums."""

    neighbour_search: NeighbourSearch = NeighbourSearch.EXACT
    """EXACT (ours) or PUBLISHED_STALE_GRID (the published code's, to measure what it changes;
    combine it with a magnet_cutoff of 1 m for the published reach: everything in the block)."""
    sort_interval: float = 180.0
    """PUBLISHED_STALE_GRID only: simulated seconds between re-listings of the grid (the
    published 180 s; it lists at t = 0, 180, 360 ... after that step's position update)."""

    def __post_init__(self) -> None:
        within = Bounds(minimum=0, maximum=MAGNITUDE_LIMIT)
        numbers = [
            f.name for f in fields(self) if not isinstance(getattr(self, f.name), bool | Enum)
        ]
        check_fields(self, {name: RANGES.get(name, within) for name in numbers})
        stiffest = self.spring * max(1.0, self.obstacle_spring_factor)
        if self.dt * math.sqrt(stiffest) >= STABLE:
            raise ValueError(
                f"dt {self.dt:g} s is too long for a contact spring of {stiffest:g}: "
                f"dt x sqrt(spring) must stay below {STABLE:g} (the published 0.01 and 1000 "
                "give 0.32), or the bodies fly apart"
            )
        if self.dt * (self.damping + self.shear) >= STABLE:
            raise ValueError(
                f"dt {self.dt:g} s is too long for damping + shear = "
                f"{self.damping + self.shear:g}: dt x (damping + shear) must stay below "
                f"{STABLE:g} (the published 0.01 x 50 is 0.5)"
            )
        if not 0 < self.r_min <= self.r_max:
            raise ValueError(f"need 0 < r_min <= r_max, not {self.r_min}, {self.r_max}")
        if not self.clamp_gap < self.blend_gap:
            raise ValueError("clamp_gap must be below blend_gap")
        if self.skin <= 0:
            raise ValueError("skin must be > 0")
        if self.half_width <= self.r_max:
            raise ValueError("half_width must exceed r_max")
        if not isinstance(self.neighbour_search, NeighbourSearch):
            choices = ", ".join(m.name for m in NeighbourSearch)
            raise ValueError(f"neighbour_search must be one of {choices}")
        if self.sort_interval < self.dt:
            raise ValueError("sort_interval must be at least one step")

    @property
    def list_radius(self) -> float:
        """Centre distance within which pairs are listed as neighbours (m)."""
        return 2 * self.r_max + self.magnet_cutoff + self.skin

    @property
    def static_force(self) -> float:
        """Largest force (N, per unit mass) a particle at rest resists."""
        return self.static_factor * self.mu * self.gravity
