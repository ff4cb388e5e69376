"""The fixed world: reflective walls, rectangular and circular obstacles, and their shadows."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
BoolArray = npt.NDArray[np.bool_]


@dataclass(frozen=True)
class Rect:
    """An axis-aligned rectangular obstacle (m), as the published x1obs x2obs y1obs y2obs."""

    x_min: float
    x_max: float
    y_min: float
    y_max: float

    def __post_init__(self) -> None:
        values = (self.x_min, self.x_max, self.y_min, self.y_max)
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"a rectangle needs finite bounds, not {values}")
        if not (self.x_min < self.x_max and self.y_min < self.y_max):
            raise ValueError(f"a rectangle needs x_min < x_max and y_min < y_max, not {values}")


@dataclass(frozen=True)
class Circle:
    """A circular obstacle (m), as the published x_cir_obs y_cir_obs r_cir_obs."""

    x: float
    y: float
    radius: float

    def __post_init__(self) -> None:
        values = (self.x, self.y, self.radius)
        if not all(math.isfinite(v) for v in values) or self.radius <= 0:
            raise ValueError(f"a circle needs a finite centre and radius > 0, not {values}")


@dataclass(frozen=True)
class Arena:
    """Obstacles inside the square world of reflective walls at +-half_width (PhysicsParams)."""

    rects: tuple[Rect, ...] = ()
    circles: tuple[Circle, ...] = ()

    def rect_array(self) -> FloatArray:
        """Rectangles as rows (x_min, x_max, y_min, y_max), for the kernels."""
        rows = [(r.x_min, r.x_max, r.y_min, r.y_max) for r in self.rects]
        return np.array(rows, dtype=np.float64).reshape(len(rows), 4)

    def circle_array(self) -> FloatArray:
        """Circles as rows (x, y, radius), for the kernels."""
        rows = [(c.x, c.y, c.radius) for c in self.circles]
        return np.array(rows, dtype=np.float64).reshape(len(rows), 3)

    def overlapping(self, x: FloatArray, y: FloatArray, radius: FloatArray) -> BoolArray:
        """Discs (centre x, y, radius) that cut into an obstacle: a placement must have none."""
        hit = np.zeros(np.shape(x), dtype=np.bool_)
        for r in self.rects:
            nearest_x = np.clip(x, r.x_min, r.x_max)
            nearest_y = np.clip(y, r.y_min, r.y_max)
            hit |= np.hypot(x - nearest_x, y - nearest_y) < radius
        for c in self.circles:
            hit |= np.hypot(x - c.x, y - c.y) < radius + c.radius
        return hit

    def shadowed(self, x: FloatArray, y: FloatArray, light_x: float, light_y: float) -> BoolArray:
        """Particles whose straight ground line from centre to the lamp's foot crosses an
        obstacle (obstacles are taller than the lamp, as the published model has it)."""
        shadow = np.zeros(np.shape(x), dtype=np.bool_)
        dx = light_x - x
        dy = light_y - y
        with np.errstate(divide="ignore", invalid="ignore"):
            for r in self.rects:
                shadow |= _segment_hits_rect(x, y, dx, dy, r)
            length2 = dx * dx + dy * dy
            for c in self.circles:
                t = np.clip(((c.x - x) * dx + (c.y - y) * dy) / length2, 0.0, 1.0)
                t = np.where(length2 > 0, t, 0.0)
                shadow |= np.hypot(x + t * dx - c.x, y + t * dy - c.y) < c.radius
        return shadow


def _segment_hits_rect(
    x: FloatArray, y: FloatArray, dx: FloatArray, dy: FloatArray, r: Rect
) -> BoolArray:
    """Slab test: does p + s (dx, dy), 0 <= s <= 1, meet the rectangle? (errstate set by caller)"""
    lo = np.zeros(np.shape(x))
    hi = np.ones(np.shape(x))
    inside = np.ones(np.shape(x), dtype=np.bool_)
    for start, delta, low, high in ((x, dx, r.x_min, r.x_max), (y, dy, r.y_min, r.y_max)):
        flat = delta == 0
        inside &= ~flat | ((start >= low) & (start <= high))
        s1 = (low - start) / delta
        s2 = (high - start) / delta
        lo = np.where(flat, lo, np.maximum(lo, np.minimum(s1, s2)))
        hi = np.where(flat, hi, np.minimum(hi, np.maximum(s1, s2)))
    return inside & (lo <= hi)
