"""The lamp and its light: inverse-square law, the SI's eq. 11 divider, and shadow modes."""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

import numpy as np
import numpy.typing as npt

from particlebot.sim.world.photocells import Photocells

ADC_FULL_SCALE = 1023
SENSOR_COUNT = 6
LOAD_OHM = 1.5e6  # R_R of SI section S3
# The SI's reference reading: 980 at r_x = 28 cm, directly under the lamp.
REFERENCE_DISTANCE_M = 0.28
REFERENCE_VALUE = 980


class ShadowMode(IntEnum):
    """What an obstacle between a particle and the lamp does (the published simulator's modes)."""

    IGNORE = 0
    """Shadows are ignored: every particle sees the lamp."""
    LAST = 1
    """A shadowed particle reads no light and moves last in the wave."""
    STILL = 2
    """A shadowed particle reads no light and does not actuate."""


@dataclass(frozen=True)
class Lamp:
    """A point source at (x, y), `height` metres above the particles' photocells."""

    x: float = 0.0
    y: float = 0.0
    height: float = REFERENCE_DISTANCE_M


class LightField:
    """ADC values a particle's photocells read at a position, following SI section S3.

    CdS cells with gamma = 1 have a resistance proportional to 1 / illuminance, illuminance
    falls with 1 / r^2 (eq. 6), so R_n = (r_n / r_x)^2 R_x (eq. 10), and the divider with the
    1.5 MOhm load reads V_n = 1023 R_R / (R_n + R_R) (eq. 11). R_x follows from the calibration
    point (eq. 13). The six cells face outwards 60 degrees apart; the one facing the lamp gets
    `direction_gain` more light (scaled by how sideways the light comes), so they differ a
    little, as real ones do, while directly under the lamp they agree. `photocells` gives each
    particle's cells a gamma and a resistance of their own (sim.world.photocells); without it
    every cell is the ideal one.
    """

    def __init__(
        self,
        lamp: Lamp | None = None,
        *,
        ref_distance: float = REFERENCE_DISTANCE_M,
        ref_value: float = REFERENCE_VALUE,
        load_ohm: float = LOAD_OHM,
        direction_gain: float = 0.02,
        noise: float = 0.0,
        seed: int = 0,
        photocells: Photocells | None = None,
    ) -> None:
        if not 0 < ref_value < ADC_FULL_SCALE:
            raise ValueError("ref_value must be inside 1..1022")
        self.lamp = lamp or Lamp()
        self.ref_distance = ref_distance
        self.ref_value = ref_value
        self.load_ohm = load_ohm
        self.direction_gain = direction_gain
        self.noise = noise
        self.photocells = photocells
        self.ref_resistance = (ADC_FULL_SCALE - ref_value) * load_ohm / ref_value  # eq. 13
        self._rng = np.random.default_rng(seed)

    def distance(self, x: float, y: float) -> float:
        """r_n: straight-line distance from the lamp to photocells at ground position (x, y)."""
        return math.hypot(x - self.lamp.x, y - self.lamp.y, self.lamp.height)

    def reading(self, x: float, y: float) -> float:
        """V_n of eq. 11 for an ideal cell at (x, y), before rounding."""
        return float(self._divider(self._resistance(self.distance(x, y))))

    def readings(
        self, xs: npt.NDArray[np.float64], ys: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        """V_n of eq. 11 for ideal cells at many positions, before rounding (the world's view)."""
        r = np.sqrt((xs - self.lamp.x) ** 2 + (ys - self.lamp.y) ** 2 + self.lamp.height**2)
        return self._divider(self._resistance(r))

    def sensor_values(
        self, x: float, y: float, heading: float = 0.0, *, particle: int = 0
    ) -> list[int]:
        """Six 10-bit ADC readings (A0..A5) at (x, y); sensor k faces heading + k * 60 deg.
        particle: whose photocells read them (the swarm's index; matters with `photocells`)."""
        values = self.sensor_matrix(np.array([x]), np.array([y]), heading, particles=[particle])
        return [int(v) for v in values[0]]

    def sensor_matrix(
        self,
        xs: npt.NDArray[np.float64],
        ys: npt.NDArray[np.float64],
        heading: float = 0.0,
        *,
        particles: npt.ArrayLike | None = None,
    ) -> npt.NDArray[np.int64]:
        """Readings for many particles at once: shape (len(xs), 6). particles: the swarm's
        index of each (default 0, 1, ...), whose photocells read them."""
        dx = np.asarray(xs, dtype=float) - self.lamp.x
        dy = np.asarray(ys, dtype=float) - self.lamp.y
        ground = np.hypot(dx, dy)
        r = np.sqrt(ground**2 + self.lamp.height**2)
        bearing = np.arctan2(-dy, -dx)  # direction from the particle towards the lamp
        sideways = ground / r
        angles = heading + np.arange(SENSOR_COUNT) * (2 * math.pi / SENSOR_COUNT)
        facing = np.cos(angles[None, :] - bearing[:, None])
        gain = 1.0 + self.direction_gain * sideways[:, None] * facing
        if self.photocells is None:
            resistance = self._resistance(r)[:, None] / gain
        else:
            rows = np.arange(len(r)) if particles is None else particles
            darkness = (r / self.ref_distance)[:, None] ** 2 / gain
            resistance = self.ref_resistance * self.photocells.relative_resistance(rows, darkness)
        values = self._divider(resistance)
        if self.noise > 0:
            values = values + self._rng.normal(0.0, self.noise, values.shape)
        return np.clip(np.rint(values), 0, ADC_FULL_SCALE).astype(np.int64)

    def distance_for_reading(self, value: float) -> float:
        """r_n from a reading by eq. 14, the inverse particles use for method A."""
        vx = self.ref_value
        ratio = vx * (ADC_FULL_SCALE - value) / (value * (ADC_FULL_SCALE - vx))
        return math.sqrt(ratio) * self.ref_distance

    def _resistance(self, r: npt.ArrayLike) -> npt.NDArray[np.float64]:
        return (np.asarray(r, dtype=float) / self.ref_distance) ** 2 * self.ref_resistance

    def _divider(self, resistance: npt.ArrayLike) -> npt.NDArray[np.float64]:
        load = self.load_ohm
        return ADC_FULL_SCALE * load / (np.asarray(resistance, dtype=float) + load)
