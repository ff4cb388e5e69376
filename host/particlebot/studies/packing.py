"""Densest packing diameter (DPD): the smallest circle that holds N equal contracted particles."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import numpy.typing as npt

from particlebot.studies.dpd_table import DPD_DIAMETERS
from particlebot.studies.published import D_MIN_M

FloatArray = npt.NDArray[np.float64]

# Work in units of the particle radius: circles of radius 1, container radius R. The DPD in
# particle diameters is then R (2R radii / 2).

_RANDOM_STARTS_UP_TO = 60
"""Below this many circles the best packings are far from a lattice: also try random starts."""
_RELAX_UP_TO = 2000
"""Above this many the hexagonal lattice is within 0.1 % of the best known packings, and relaxing
it would take minutes: the lattice is the answer."""
_PENALTIES = (1.0, 10.0, 1e2, 1e3, 1e4, 1e5, 1e6)
"""Overlap penalties of the continuation: each stage starts where the last one ended; steps of 10
keep L-BFGS in its basin (bigger steps jam the packing far from dense)."""
_DECIMALS = 4
"""DPDs are rounded to 1e-4 diameters (15 um) so that the same N gives the same geometry, and the
same run ids, on every machine whatever the last bits of the optimiser."""


def densest_packing_diameters(n: int) -> float:
    """DPD of n particles, in minimum particle diameters (Table S6's unit).

    Read from the table tools/gen_dpd_table.py computed with compute_densest_packing() for the
    sizes studies use; computed here for any other n (seconds up to a minute for n <= 2000, under
    one second above).
    """
    if n < 1:
        raise ValueError(f"a packing needs at least one particle, not {n}")
    tabled = DPD_DIAMETERS.get(n)
    return tabled if tabled is not None else compute_densest_packing(n)


def densest_packing_diameter_m(n: int) -> float:
    """DPD of n particles in metres (Table S5's quantity, in m)."""
    return densest_packing_diameters(n) * D_MIN_M


def hexagonal_lattice_diameters(n: int) -> float:
    """The hexagonal lattice's DPD alone (in diameters): what the relaxation starts from."""
    return _hexagonal(n)[0]


@lru_cache(maxsize=64)
def compute_densest_packing(n: int) -> float:
    """The best packing found, in diameters, by: a hexagonal lattice clipped to the circle with its
    centre offset chosen on a grid (any n, an upper bound); for n <= 2000, that lattice relaxed by
    penalty continuation (overlaps and the container's edge penalised, the container's radius
    minimised); for n <= 60, also four seeded random starts. Deterministic; cached per process."""
    if n == 1:
        return 1.0
    best, centres = _hexagonal(n)
    if n <= _RELAX_UP_TO:
        best = min(best, _relaxed(centres, best))
    if n <= _RANDOM_STARTS_UP_TO:
        rng = np.random.default_rng(n)
        for _ in range(4):
            start, radius = _random_start(n, rng)
            best = min(best, _relaxed(start, radius))
    return round(best, _DECIMALS)


@lru_cache(maxsize=64)
def _hexagonal(n: int) -> tuple[float, FloatArray]:
    """Container radius of the best offset of a hexagonal lattice (spacing 2), and its centres."""
    # A finer grid of offsets matters for small n only (the same answer to 1e-4 above 2000).
    grid = 24 if n <= _RELAX_UP_TO else 12
    m = int(np.sqrt(n / 0.9) * 0.7) + 6
    i, j = np.meshgrid(np.arange(-m, m + 1), np.arange(-m, m + 1))
    lattice = np.stack([(2 * i + j).ravel(), (np.sqrt(3) * j).ravel()], axis=1).astype(float)
    best_radius, best_centres = np.inf, lattice[:n]
    # Offsets over one cell of the lattice cover every distinct placement of the container.
    for u in np.linspace(0.0, 1.0, grid, endpoint=False):
        for v in np.linspace(0.0, 1.0, grid, endpoint=False):
            offset = np.array([2 * u + v, np.sqrt(3) * v])
            distance = np.hypot(*(lattice - offset).T)
            nearest = np.argpartition(distance, n - 1)[:n]
            radius = float(distance[nearest].max()) + 1.0
            if radius < best_radius:
                best_radius, best_centres = radius, lattice[nearest] - offset
    return best_radius, best_centres


def _random_start(n: int, rng: np.random.Generator) -> tuple[FloatArray, float]:
    radius = np.sqrt(n / 0.9069) * 1.15 + 1.0
    angle = rng.uniform(0.0, 2 * np.pi, n)
    r = (radius - 1.0) * np.sqrt(rng.uniform(0.0, 1.0, n))
    return np.stack([r * np.cos(angle), r * np.sin(angle)], axis=1), radius


def _penalised(
    z: FloatArray, n: int, weight: float, first: npt.NDArray[np.intp], second: npt.NDArray[np.intp]
) -> tuple[float, FloatArray]:
    """Container radius + weight x (squared overlaps of the listed pairs and with the edge)."""
    x = z[:-1].reshape(n, 2)
    radius = z[-1]
    d = x[first] - x[second]
    dist = np.maximum(np.sqrt((d**2).sum(axis=1)), 1e-12)
    overlap = np.maximum(0.0, 2.0 - dist)
    energy = float((overlap**2).sum())
    pair_grad = (-2.0 * overlap / dist)[:, None] * d
    grad = np.zeros((n, 2))
    for axis in (0, 1):
        grad[:, axis] = np.bincount(first, pair_grad[:, axis], n) - np.bincount(
            second, pair_grad[:, axis], n
        )
    reach = np.maximum(np.sqrt((x**2).sum(axis=1)), 1e-12)
    outside = np.maximum(0.0, reach + 1.0 - radius)
    energy += float((outside**2).sum())
    grad += (2.0 * outside / reach)[:, None] * x
    value = radius + weight * energy
    return value, np.append(weight * grad.ravel(), 1.0 - 2.0 * weight * outside.sum())


def _relaxed(centres: FloatArray, radius: float) -> float:
    """Shrinks the container around centres by penalty continuation; returns a feasible radius."""
    # scipy is imported where it works, so that `particlebot study --help` does not load it.
    from scipy.optimize import minimize
    from scipy.spatial import cKDTree

    n = len(centres)
    z = np.append(centres.ravel(), radius)
    for weight in _PENALTIES:
        if n <= _RANDOM_STARTS_UP_TO:
            # Every pair: circles from a random start travel far in the first stages.
            first, second = np.triu_indices(n, 1)
        else:
            # Pairs within reach of touching; a stage moves circles far less than this margin.
            pairs = cKDTree(z[:-1].reshape(n, 2)).query_pairs(2.6, output_type="ndarray")
            first, second = pairs[:, 0], pairs[:, 1]
        z = minimize(
            _penalised,
            z,
            args=(n, weight, first, second),
            jac=True,
            method="L-BFGS-B",
            options={"maxiter": 2000},
        ).x
    return _feasible_radius(z[:-1].reshape(n, 2))


def _feasible_radius(centres: FloatArray) -> float:
    """The container radius of centres after spreading them just enough that none overlap: the
    penalty leaves overlaps of order 1/weight, and the answer must be a real packing."""
    from scipy.spatial import cKDTree

    nearest = cKDTree(centres).query(centres, k=2)[0][:, 1].min()
    scale = max(1.0, 2.0 / float(nearest))
    return float((np.sqrt((centres**2).sum(axis=1)) * scale).max()) + 1.0
