"""The paper's published numbers for its simulation studies (SI section S9), transcribed once."""

from __future__ import annotations

import math
from dataclasses import dataclass

# ---- the published model's numbers the studies are defined in ---------------------------------
# From the published simulator's defaults (shared notes, simulation parameters). Kept here, not
# imported from the world, so that defining and listing studies needs no numba; a test holds them
# to the world's PhysicsParams and the published controller's settings.

R_MIN_M = 0.0775
"""Contracted particle radius (m)."""
R_MAX_M = 0.1175
"""Fully expanded particle radius (m)."""
D_MIN_M = 2 * R_MIN_M
"""Minimum particle diameter (m): the unit of Table S6, of gap thickness and of sensor noise."""
CYCLE_S = 12.0
"""One expansion-contraction cycle of the published controller, (Nx + 1) x rise period (s)."""
DT_S = 0.01
"""The published time step (s): used to estimate a run's cost in particle-steps."""


# ---- the published simulator's rendering camera -------------------------------------------------
# Its first commit's main.cpp sets, per swarm size, a densest-packing diameter and a light factor,
# then hangs the camera at their product straight above the world's origin, and renders a
# 60-degree (vertical) perspective at 1920x1080. docs/studies-camera.md tests the hypothesis that
# Table S3 was read from these videos with one pixel scale, the 1,000-particle camera's.

CAMERA_RULE: tuple[tuple[int, float, float], ...] = (
    (11, 0.591, 16.0),
    (101, 1.718, 8.0),
    (1001, 5.264, 4.0),
    (10001, 16.449, 2.0),
)
"""(largest N, densest-packing diameter m, light factor): camera height = diameter x factor."""
CAMERA_IMAGE_SIZE = (1920, 1080)
CAMERA_FIELD_OF_VIEW_DEG = 60.0
"""gluPerspective(60.0, w / h, ...): the vertical field of view."""
ONE_SCALE_PARTICLES = 1000
"""The swarm size whose camera's pixel scale the hypothesis takes for every size."""


def camera_height_m(particles: int) -> float:
    """The published rendering camera's height for a swarm of that size (m): 9.46, 13.74, 21.06
    or 32.90."""
    for largest, diameter_m, factor in CAMERA_RULE:
        if particles <= largest:
            return diameter_m * factor
    raise ValueError(f"the published simulator has no camera for {particles} particles")


def camera_px_per_m(height_m: float) -> float:
    """Pixels per metre of floor seen straight down from that height (935 / height)."""
    half_height = CAMERA_IMAGE_SIZE[1] / 2
    return half_height / math.tan(math.radians(CAMERA_FIELD_OF_VIEW_DEG / 2)) / height_m


def paper_camera_factor(particles: int) -> float:
    """What one pixel scale (the 1,000-particle camera's) multiplies a true length or speed by
    for a swarm of that size: 21.06 / its camera's height (x2.23, x1.53, x1, x0.64)."""
    return camera_height_m(ONE_SCALE_PARTICLES) / camera_height_m(particles)


def speed_to_percent_diameter_per_cycle(speed_mm_s: float) -> float:
    """Table S4's unit from Table S3's: mm/s x 12 s per cycle, as a percentage of 155 mm."""
    return speed_mm_s * CYCLE_S / (D_MIN_M * 1000.0) * 100.0


@dataclass(frozen=True)
class Published:
    """One published cell: mean and one standard deviation, in the table's unit."""

    mean: float
    sd: float


# ---- Tables S3 and S4: speed against the fraction of dead particles -----------------------------
# 11 random configurations per cell, 2 h simulated, the first 30 min left out.

DEAD_SIZES = (10, 100, 1000, 10000)
DEAD_FRACTIONS = (0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)


def _row(*cells: tuple[float, float]) -> dict[float, Published]:
    return {f: Published(m, s) for f, (m, s) in zip(DEAD_FRACTIONS, cells, strict=True)}


TABLE_S3_MM_S: dict[int, dict[float, Published]] = {
    10: _row(
        (1.24, 0.44), (0.95, 0.50), (0.74, 0.47), (0.37, 0.50), (0.21, 0.26),
        (0.17, 0.30), (0.01, 0.07), (-0.01, 0.04), (-0.00, 0.00),
    ),
    # The 40 % cell is printed as 0.84 +- 0.04: Table S4's matching 0.65 % min. diameter/cycle and
    # its neighbours (0.16 at 30 %, 0.03 at 50 %) show a dropped zero. Read as 0.084.
    100: _row(
        (0.64, 0.19), (0.43, 0.09), (0.31, 0.11), (0.16, 0.07), (0.084, 0.04),
        (0.03, 0.02), (0.00, 0.00), (0.00, 0.00), (0.00, 0.00),
    ),
    # Likewise printed as 0.63 +- 0.01 at 40 %; Table S4 gives 0.49 %: read as 0.063.
    1000: _row(
        (0.45, 0.05), (0.33, 0.04), (0.22, 0.02), (0.13, 0.02), (0.063, 0.01),
        (0.02, 0.01), (0.01, 0.01), (0.00, 0.00), (0.00, 0.00),
    ),
    # The 80 % cell is printed "0.01+0.00"; read as 0.01 +- 0.00.
    10000: _row(
        (0.27, 0.01), (0.20, 0.01), (0.14, 0.01), (0.09, 0.01), (0.05, 0.00),
        (0.02, 0.00), (0.01, 0.00), (0.00, 0.00), (0.01, 0.00),
    ),
}  # fmt: skip
"""Table S3: mean speed toward the light (mm/s), by swarm size and dead fraction."""

TABLE_S4_PERCENT: dict[int, dict[float, Published]] = {
    10: _row(
        (9.60, 3.40), (7.39, 3.87), (5.76, 3.63), (2.88, 3.82), (1.65, 2.01),
        (1.34, 2.33), (0.06, 0.54), (-0.07, 0.32), (-0.01, 0.02),
    ),
    100: _row(
        (4.99, 1.43), (3.33, 0.70), (2.44, 0.82), (1.22, 0.51), (0.65, 0.33),
        (0.22, 0.14), (0.03, 0.03), (0.03, 0.01), (0.00, 0.00),
    ),
    1000: _row(
        (3.47, 0.41), (2.53, 0.28), (1.73, 0.18), (0.98, 0.17), (0.49, 0.11),
        (0.19, 0.09), (0.08, 0.05), (0.08, 0.00), (0.00, 0.00),
    ),
    10000: _row(
        (2.09, 0.07), (1.57, 0.08), (1.12, 0.06), (0.73, 0.04), (0.41, 0.02),
        (0.19, 0.02), (0.07, 0.00), (0.07, 0.00), (0.01, 0.00),
    ),
}  # fmt: skip
"""Table S4: the same speeds in % of the minimum diameter per 12 s cycle."""

TABLE_S4_DISAGREES_WITH_S3 = frozenset({(1000, 0.7), (10000, 0.7), (10000, 0.8), (10, 0.3)})
"""Cells where Table S4 is not Table S3 converted, whatever the rounding: at 70 % for 1,000 and
10,000 particles 0.00 mm/s is printed as 0.08 and 0.07 %/cycle (the 60 % column's values); at 80 %
for 10,000 both tables print "0.01+0.00", but 0.01 mm/s would be 0.08 %/cycle; for 10 particles
at 30 % the sd 0.50 mm/s would be 3.87, not 3.82. Table S3 is the reference in all of them."""


# ---- Tables S5 and S6: densest packing diameter and the gap sizes -------------------------------

GAP_FRACTIONS = (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)
"""Gap sizes as fractions of the densest packing diameter (DPD)."""
GAP_RUNS = 10
GAP_CYCLES = 4500
GAP_LIGHT_DPD = 2.5
"""Light source, in DPD from the swarm's initial centroid."""
GAP_OBSTACLE_DPD = 0.75
"""Obstacle, in DPD from the swarm's initial centroid."""

TABLE_S5_DPD_CM: dict[int, float] = {
    10: 59.1, 50: 123.2, 100: 171.8, 500: 374.0, 1000: 526.4, 5000: 1165.8, 10000: 1644.9,
}  # fmt: skip
"""Table S5: densest packing diameter (cm)."""

TABLE_S5_GAP_CM: dict[int, tuple[float, ...]] = {
    10: (11.82, 17.73, 23.64, 29.55, 35.46, 41.37, 47.28),
    50: (24.64, 36.96, 49.28, 61.60, 73.92, 86.24, 98.56),
    100: (34.36, 51.54, 68.72, 85.90, 103.08, 120.26, 137.44),
    500: (74.80, 112.20, 149.60, 187.00, 224.40, 261.80, 299.20),
    1000: (105.28, 157.92, 210.56, 263.20, 315.84, 368.48, 421.12),
    5000: (233.16, 349.74, 466.32, 582.90, 699.48, 816.06, 932.64),
    10000: (328.98, 493.47, 657.96, 822.45, 986.94, 1151.43, 1315.92),
}
"""Table S5: gap sizes (cm) at GAP_FRACTIONS of the DPD."""

TABLE_S6_DPD_DIAMETERS: dict[int, float] = {
    10: 3.81, 50: 7.95, 100: 11.08, 500: 24.13, 1000: 33.96, 5000: 75.21, 10000: 106.12,
}  # fmt: skip
"""Table S6: densest packing diameter in minimum particle diameters."""

TABLE_S6_GAP_DIAMETERS: dict[int, tuple[float, ...]] = {
    10: (0.76, 1.14, 1.53, 1.91, 2.29, 2.67, 3.05),
    50: (1.59, 2.38, 3.18, 3.97, 4.77, 5.56, 6.36),
    100: (2.22, 3.33, 4.43, 5.54, 6.65, 7.76, 8.87),
    500: (4.83, 7.24, 9.65, 12.06, 14.48, 16.89, 19.30),
    1000: (6.79, 10.19, 13.58, 16.98, 20.38, 23.77, 27.17),
    5000: (15.04, 22.56, 30.09, 37.61, 45.13, 52.65, 60.17),
    10000: (21.22, 31.84, 42.45, 53.06, 63.67, 74.29, 84.90),
}
"""Table S6: gap sizes in minimum particle diameters."""


# ---- Figs. S18-S21: published as figures, so only their stated findings --------------------------

FIG_S18_FINDING = (
    "success passing the gap grows with the number of particles and varies less; "
    "the best performance is observed with 1,000 particles"
)
CARRY_SIZES = (10, 100, 1000, 10000)
CARRY_RADIUS_FRACTIONS = (0.2, 0.4, 0.6, 0.8)
"""Object radius as a fraction of the DPD. The SI's text says radius, Fig. S19's caption says
diameter; the studies follow the text."""
FIG_S19_CYCLES = 3000
FIG_S19_FINDING = (
    "10 and 100 particles cannot move the object; 1,000 carry it a significant distance but leave "
    "smaller objects behind; 10,000 carry it consistently"
)
NOISE_SIZE = 10000
NOISE_SEEDS = 11
FIG_S20_RELATIVE_SPEED_AT_ONE_DIAMETER = 0.67
"""Fig. S20: a distance-estimation error of one minimum diameter (sd) costs 33 % of the speed."""
FIG_S20_STANDSTILL_BEYOND_DIAMETERS = 2.0
"""Fig. S20: beyond an error of two diameters the robot is stationary."""
FIG_S21_FINDING = (
    "speed and direction toward the light do not change when the robot doubles its size by "
    "annexing free particles (and detaching dead ones)"
)
