"""A WorldView of particles that stay where they are put: drives a controller without the world."""

from __future__ import annotations

import numpy as np

from particlebot.sim.particles.model.controller import BoolArray, FloatArray


class StaticView:
    """Particles at fixed positions with given light readings; time is whatever `t` is set to.

    For tests and benchmarks of controllers: the real world moves the particles and computes the
    light, this one only reports what it was given (change `readings` or `t` between steps).
    """

    def __init__(
        self,
        x: FloatArray,
        y: FloatArray,
        readings: FloatArray,
        *,
        lamp: tuple[float, float] = (0.0, 0.0),
        r_min: float = 0.0775,
        r_max: float = 0.1175,
    ) -> None:
        self._x = np.asarray(x, dtype=np.float64)
        self._y = np.asarray(y, dtype=np.float64)
        if self._x.shape != self._y.shape or self._x.ndim != 1:
            raise ValueError("x and y must be 1-D arrays of the same length")
        self.readings = np.asarray(readings, dtype=np.float64)
        self.lamp = lamp
        self.t = 0.0
        self._r_min = r_min
        self._r_max = r_max
        self.alive = np.ones(self._x.shape, dtype=np.bool_)

    @property
    def count(self) -> int:
        return int(self._x.shape[0])

    @property
    def x(self) -> FloatArray:
        return self._x

    @property
    def y(self) -> FloatArray:
        return self._y

    @property
    def r_min(self) -> float:
        return self._r_min

    @property
    def r_max(self) -> float:
        return self._r_max

    def light_distance(self) -> FloatArray:
        return np.hypot(self._x - self.lamp[0], self._y - self.lamp[1])

    def light_readings(self) -> FloatArray:
        return self.readings

    def acting(self) -> BoolArray:
        return self.alive
