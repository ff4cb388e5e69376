"""How unlike one another simulated CdS photocells are: each cell's gamma (eq. 7) and resistance.

The light model (particlebot.sim.world.light) asks this module for one thing: a cell's resistance,
relative to the reference resistance R_x of SI eq. 13, under light that is `darkness` times
dimmer than at the reference point. An ideal cell (eq. 8, gamma = 1) answers `darkness`; a real
CdS cell follows R = factor * R_x * darkness^gamma, with its own gamma and its own factor. Those
two numbers per cell are all a calibration (`particlebot calibrate sensors`) has to find.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

SENSOR_COUNT = 6
MAX_SPREAD = 0.5
FACTOR_SPREAD = 3.0
"""A spread s gives gamma within 1 +- s and a resistance factor within e^(+-3 s): s = 0.1 makes
gamma 0.9-1.1 and factors 0.74-1.35, about what one batch of CdS cells of one type shows."""
_STREAM = 0x9407C311
"""Mixed into the seed, so the cells do not follow the particles' other random numbers."""


@dataclass(frozen=True)
class Photocells:
    """gamma[p, k] and factor[p, k] of photocell k (A0..A5) of the swarm's particle p."""

    gamma: npt.NDArray[np.float64]
    factor: npt.NDArray[np.float64]

    @classmethod
    def spread(cls, count: int, spread: float, seed: int) -> Photocells:
        """count particles' cells drawn uniformly within the spread (see FACTOR_SPREAD); the
        same cells for the same seed, and particle p's cells do not depend on count."""
        if not 0 <= spread <= MAX_SPREAD:
            raise ValueError(f"photocell spread must be 0..{MAX_SPREAD}, not {spread}")
        gamma = np.ones((count, SENSOR_COUNT))
        factor = np.ones((count, SENSOR_COUNT))
        for p in range(count):
            rng = np.random.default_rng([_STREAM, seed, p])
            gamma[p] = rng.uniform(1 - spread, 1 + spread, SENSOR_COUNT)
            factor[p] = np.exp(rng.uniform(-FACTOR_SPREAD, FACTOR_SPREAD, SENSOR_COUNT) * spread)
        return cls(gamma, factor)

    def relative_resistance(
        self, rows: npt.ArrayLike, darkness: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        """R / R_x of the cells of particles `rows` (shape (n,)) under light `darkness` times
        dimmer than at the reference point (shape (n, 6)): factor * darkness^gamma."""
        index = np.asarray(rows, dtype=np.intp)
        return self.factor[index] * darkness ** self.gamma[index]
